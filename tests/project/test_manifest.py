"""``results/MANIFEST.md`` lists every file under ``results/`` with a command and real commits, every study has its
pre-registration, the files the README links are marked, and every link into ``results/`` resolves."""

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "results"
MANIFEST = RESULTS / "MANIFEST.md"

MARK = "★"
"""The mark of a file the README quotes."""
# the first cell of a manifest row: [name](folder/file), marked or not
ROW = re.compile(rf"^\| (?:{MARK} )?\[[^\]]+\]\(([^)]+)\) \|", re.MULTILINE)
# a part's command list above its table: "- C1: `...`"
COMMAND = re.compile(r"^- (C\d+): \S", re.MULTILINE)
# a Markdown link or image target, and a path in inline code
LINK = re.compile(r"\]\(([^)\s]+)\)")
CODE = re.compile(r"`([^`\s]*results/[^`\s]*)`")


def manifest_entries() -> list[str]:
    return ROW.findall(MANIFEST.read_text())


def documents() -> list[Path]:
    """The README, the pages under ``docs/`` (not the site built into ``docs/_build/``, nor the records' pages the
    build copies into ``docs/results/``) and the manifest."""
    built = {"_build", "results"}
    pages = [p for p in sorted((ROOT / "docs").rglob("*.md")) if p.relative_to(ROOT / "docs").parts[0] not in built]
    return [ROOT / "README.md", *pages, MANIFEST]


def ignored() -> set[str]:
    """Files under ``results/`` that git ignores: the run folders a command writes beside its results."""
    try:
        out = subprocess.run(
            ["git", "ls-files", "--others", "--ignored", "--exclude-standard", "results"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):  # not a git checkout
        return set()
    return {Path(p).relative_to("results").as_posix() for p in out.splitlines()}


def test_every_result_file_is_in_the_manifest() -> None:
    listed = set(manifest_entries())
    on_disk = {p.relative_to(RESULTS).as_posix() for p in RESULTS.rglob("*") if p.is_file() and p != MANIFEST}
    on_disk -= ignored()
    assert sorted(on_disk - listed) == [], "files under results/ that MANIFEST.md does not list"


def test_every_manifest_entry_names_a_file() -> None:
    entries = manifest_entries()
    assert entries, "no rows found in results/MANIFEST.md"
    assert len(entries) == len(set(entries)), "a file is listed twice"
    assert [e for e in entries if not (RESULTS / e).is_file()] == []


def rows_by_section() -> list[tuple[set[str], list[list[str]]]]:
    """Per ``###`` section of the manifest: the command labels it defines and the cells of its rows."""
    sections = [s for s in re.split(r"^### ", MANIFEST.read_text(), flags=re.MULTILINE)[1:]]
    out = []
    for section in sections:
        rows = [line for line in section.splitlines() if ROW.match(line + "\n")]
        cells = [[c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]] for line in rows]
        out.append((set(COMMAND.findall(section)), cells))
    return out


def test_every_manifest_row_has_a_command_and_commits() -> None:
    sections = rows_by_section()
    assert sum(len(rows) for _, rows in sections) == len(manifest_entries()), "a row outside a ### section"
    for labels, rows in sections:
        for cells in rows:
            assert len(cells) == 5, cells
            assert cells[2] == "text" or cells[2] in labels, f"command {cells[2]!r} not listed above its table: {cells}"
            assert all(re.fullmatch(r"[0-9a-f]{7,40}", c) for c in cells[3:]), cells


def test_the_manifest_commits_exist() -> None:
    commits = sorted({c for _, rows in rows_by_section() for cells in rows for c in cells[3:]})
    try:
        out = subprocess.run(
            ["git", "cat-file", "--batch-check"],
            cwd=ROOT,
            input="".join(f"{c}^{{commit}}\n" for c in commits),
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    if "fatal: not a git repository" in out or not out:
        pytest.skip("not a git checkout")
    missing = [c for c, line in zip(commits, out.splitlines(), strict=True) if line.endswith("missing")]
    assert missing == [], "commits named in MANIFEST.md that git does not have"


def test_every_study_has_its_preregistration() -> None:
    studies = [p for p in RESULTS.iterdir() if p.is_dir()]
    assert studies
    assert [p.name for p in studies if not (p / "preregistration.md").is_file()] == []
    headings = re.findall(r"^## (\S+)$", MANIFEST.read_text(), flags=re.MULTILINE)
    assert sorted(headings) == sorted(p.name for p in studies), "one ## heading per study folder"


def test_the_files_the_readme_links_are_marked() -> None:
    marked = set(re.findall(rf"^\| {MARK} \[[^\]]+\]\(([^)]+)\) \|", MANIFEST.read_text(), flags=re.MULTILINE))
    linked = set()
    for target in LINK.findall((ROOT / "README.md").read_text()):
        path = (ROOT / target.split("#")[0]).resolve()
        if path.is_file() and RESULTS in path.parents and path != MANIFEST:
            linked.add(path.relative_to(RESULTS).as_posix())
    assert sorted(linked - marked) == [], f"files the README links that MANIFEST.md does not mark {MARK}"


def test_links_into_results_resolve() -> None:
    broken = []
    for doc in documents():
        text = doc.read_text()
        for target in LINK.findall(text):
            path = target.split("#")[0]
            if "://" in path or "results/" not in (doc.parent / path).resolve().as_posix():
                continue
            if not (doc.parent / path).resolve().exists():
                broken.append(f"{doc.relative_to(ROOT)}: {target}")
        for target in CODE.findall(text):
            if "<" in target or "*" in target:
                continue
            base = doc.parent if target.startswith("../") else ROOT
            if target.startswith("results/") or target.startswith("../results/"):
                if not (base / target).resolve().exists():
                    broken.append(f"{doc.relative_to(ROOT)}: `{target}`")
    assert broken == []


def test_relative_links_in_the_docs_resolve() -> None:
    """Also in the results' own pages (records name old file names in code spans, as written, but link the new)."""
    broken = []
    for doc in sorted({*documents(), *RESULTS.rglob("*.md")}):
        for target in LINK.findall(doc.read_text()):
            path = target.split("#")[0]
            if path and "://" not in path and not path.startswith("mailto:"):
                if not (doc.parent / path).resolve().exists():
                    broken.append(f"{doc.relative_to(ROOT)}: {target}")
    assert broken == []


def git(*args: str, stdin: str | None = None) -> str:
    """The output of ``git args`` in the checkout; skips the test outside a git checkout."""
    try:
        return subprocess.run(["git", *args], cwd=ROOT, input=stdin, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout (or git is missing)")


def made_by() -> dict[str, set[str]]:
    """Per commit (full hash), the contents (blob hashes) it changed a file to, pure moves left out."""
    made: dict[str, set[str]] = {}
    commit = ""
    for line in git("log", "-M", "--format=>%H", "--raw", "--no-abbrev", "HEAD").splitlines():
        if line.startswith(">"):
            commit = line[1:]
            made[commit] = set()
        elif line.startswith(":"):
            _, _, _, new, status = line.split("\t")[0].split()[:5]
            if status != "R100":
                made[commit].add(new)
    return made


def test_each_file_is_as_its_rows_commit_made_it() -> None:
    entries = [
        (re.search(r"\]\(([^)]+)\)", cells[0]).group(1), cells) for _, rows in rows_by_section() for cells in rows
    ]
    contents = git("hash-object", "--stdin-paths", stdin="".join(f"results/{path}\n" for path, _ in entries)).split()
    made = made_by()
    wrong = []
    for (path, cells), content in zip(entries, contents, strict=True):
        commits = [c for c in made if c.startswith(cells[4])]
        if len(commits) != 1 or content not in made[commits[0]]:
            wrong.append(f"{path}: rows {cells[4]} did not make its content (`git log --follow -- results/{path}`)")
    assert wrong == []


def test_each_code_commit_is_its_rows_commit_or_before() -> None:
    pairs = sorted({(cells[3], cells[4]) for _, rows in rows_by_section() for cells in rows})
    git("rev-parse", "HEAD")  # skips outside a checkout
    late = [
        pair for pair in pairs if subprocess.run(["git", "merge-base", "--is-ancestor", *pair], cwd=ROOT).returncode
    ]
    assert late == [], "code commits after their rows commit"
