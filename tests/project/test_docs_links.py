"""The documentation site's link rewriting (``docs/_ext/repository_links.py``): repository files become downloads,
pages stay pages, README sections resolve from ``docs/``."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("repository_links", ROOT / "docs" / "_ext" / "repository_links.py")
links = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(links)


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "page.md").write_text("# page\n")
    (tmp_path / "results" / "study").mkdir(parents=True)
    (tmp_path / "results" / "study" / "table.md").write_text("| a |\n")
    (tmp_path / "README.md").write_text(
        "# t\n\n## Install\n\nSee [page](docs/page.md#x) and [table](results/study/table.md).\n\n## Next\n\nno\n"
    )
    return tmp_path


def test_a_repository_file_becomes_a_download_and_a_page_stays_a_page(repo: Path) -> None:
    docs = repo / "docs"
    text = "[t](../results/study/table.md) [p](page.md#a) [w](https://x.org/a.md) ![i](../results/study/table.md)"
    out = links.rewrite_links(text, docs, docs, docs)
    assert out == (
        "[t](path:../results/study/table.md) [p](page.md#a) [w](https://x.org/a.md) ![i](../results/study/table.md)"
    )


def test_links_in_code_fences_and_to_folders_are_kept(repo: Path) -> None:
    docs = repo / "docs"
    text = "```\n[t](../results/study/table.md)\n```\n[f](../results/study/)"
    assert links.rewrite_links(text, docs, docs, docs) == text


def test_a_readme_section_is_cut_at_its_lines_and_its_links_resolve_from_docs(repo: Path) -> None:
    section = links.readme_section(repo / "README.md", "## Install", "## Next")
    assert section == "\nSee [page](docs/page.md#x) and [table](results/study/table.md).\n"
    out = links.rewrite_links(section, repo, repo / "docs", repo / "docs")
    assert "[page](page.md#x)" in out and "[table](path:../results/study/table.md)" in out


def test_a_missing_readme_line_is_an_error_naming_it(repo: Path) -> None:
    with pytest.raises(ValueError, match="## Usage"):
        links.readme_section(repo / "README.md", "## Usage", "## Next")
