"""The documentation site's link rewriting (``docs/_ext/repository_links.py``): the studies' records become pages,
other repository files downloads, pages stay pages, README sections resolve from ``docs/``; and every study's table
and pre-registration is linked from the docs."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
UNLINKED: list[str] = []
"""Records of a study whose page is being written (issue 67); each goes once its page links it."""
_spec = importlib.util.spec_from_file_location("repository_links", ROOT / "docs" / "_ext" / "repository_links.py")
links = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(links)


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "page.md").write_text("# page\n")
    (tmp_path / "results" / "study").mkdir(parents=True)
    (tmp_path / "results" / "study" / "table.md").write_text("| a |\n")
    (tmp_path / "results" / "study" / "rows.csv").write_text("a\n1\n")
    (tmp_path / "README.md").write_text(
        "# t\n\n## Install\n\nSee [page](docs/page.md#x) and [table](results/study/table.md).\n\n## Next\n\nno\n"
    )
    return tmp_path


def test_a_record_becomes_a_page_another_file_a_download_and_a_page_stays_a_page(repo: Path) -> None:
    docs = repo / "docs"
    text = "[t](../results/study/table.md#x) [r](../results/study/rows.csv) [p](page.md#a) [w](https://x.org/a.md)"
    assert links.rewrite_links(text, docs, docs, docs) == (
        "[t](results/study/table.md#x) [r](path:../results/study/rows.csv) [p](page.md#a) [w](https://x.org/a.md)"
    )
    assert links.rewrite_links("![i](../results/study/f.png)", docs, docs, docs) == "![i](../results/study/f.png)"


def test_a_study_part_s_folder_goes_to_its_table_and_other_folders_and_code_fences_are_kept(repo: Path) -> None:
    docs = repo / "docs"
    (repo / "results" / "empty").mkdir()
    assert links.rewrite_links("[f](../results/study/)", docs, docs, docs) == "[f](results/study/table.md)"
    text = "```\n[t](../results/study/table.md)\n```\n[e](../results/empty/)"
    assert links.rewrite_links(text, docs, docs, docs) == text


def test_the_records_pages_are_kept_in_step_with_the_records(repo: Path) -> None:
    docs = repo / "docs"
    stale = docs / "results" / "gone" / "table.md"
    stale.parent.mkdir(parents=True)
    stale.write_text("a record since removed")
    assert links.mirror_records(docs) == [docs / "results" / "study" / "table.md"]
    assert (docs / "results" / "study" / "table.md").read_text() == "| a |\n" and not stale.exists()
    (repo / "results" / "study" / "table.md").write_text("| b |\n")
    links.mirror_records(docs)
    assert (docs / "results" / "study" / "table.md").read_text() == "| b |\n"


def test_a_record_s_page_is_titled_with_consecutive_headings_its_links_from_its_folder(repo: Path) -> None:
    docs = repo / "docs"
    text = "### Part\n\n[r](rows.csv) [t](table.md) [p](../../docs/page.md) ![f](f.png)\n\n#### Sub\n"
    page = links.record_source(text, "results/study/table", docs)
    assert page == (
        "---\norphan: true\n---\n\n# results/study/table.md\n\n## Part\n\n[r](path:../../../results/study/rows.csv) "
        "[t](table.md) [p](../../page.md) ![f](../../../results/study/f.png)\n\n### Sub\n"
    )
    assert links.record_source("# Title\n", "results/study/table", docs).endswith("\n# Title\n")


def test_a_readme_section_is_cut_at_its_lines_and_its_links_resolve_from_docs(repo: Path) -> None:
    section = links.readme_section(repo / "README.md", "## Install", "## Next")
    assert section == "\nSee [page](docs/page.md#x) and [table](results/study/table.md).\n"
    out = links.rewrite_links(section, repo, repo / "docs", repo / "docs")
    assert "[page](page.md#x)" in out and "[table](results/study/table.md)" in out


def test_a_missing_readme_line_is_an_error_naming_it(repo: Path) -> None:
    with pytest.raises(ValueError, match="## Usage"):
        links.readme_section(repo / "README.md", "## Usage", "## Next")


def test_every_study_s_table_and_pre_registration_is_linked_from_the_docs() -> None:
    docs = ROOT / "docs"
    targets = {
        (docs / match[3].partition("#")[0]).resolve()
        for page in docs.glob("*.md")
        for match in links.LINK.finditer(page.read_text(encoding="utf-8"))
    }
    records = [path for study in (ROOT / "results").iterdir() for path in study.glob("*.md")]
    assert any(path.name == "preregistration.md" for path in records)
    assert [str(path.relative_to(ROOT)) for path in records if path.resolve() not in targets] == UNLINKED
