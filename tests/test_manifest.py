"""``results/MANIFEST.md`` lists every file under ``results/``, and every link into ``results/`` resolves."""

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "results"
MANIFEST = RESULTS / "MANIFEST.md"

# the first cell of a manifest row: [name](folder/file)
ROW = re.compile(r"^\| \[[^\]]+\]\(([^)]+)\) \|", re.MULTILINE)
# a Markdown link or image target, and a path in inline code
LINK = re.compile(r"\]\(([^)\s]+)\)")
CODE = re.compile(r"`([^`\s]*results/[^`\s]*)`")


def manifest_entries() -> list[str]:
    return ROW.findall(MANIFEST.read_text())


def documents() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")), MANIFEST]


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


def test_every_manifest_row_has_a_command_and_commits() -> None:
    rows = [line for line in MANIFEST.read_text().splitlines() if ROW.match(line + "\n")]
    for line in rows:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        assert len(cells) == 6, line
        assert cells[3], f"no command: {line}"
        assert re.fullmatch(r"[0-9a-f]{7,40}", cells[4]) and re.fullmatch(r"[0-9a-f]{7,40}", cells[5]), line


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
    broken = []
    for doc in documents():
        for target in LINK.findall(doc.read_text()):
            path = target.split("#")[0]
            if path and "://" not in path and not path.startswith("mailto:"):
                if not (doc.parent / path).resolve().exists():
                    broken.append(f"{doc.relative_to(ROOT)}: {target}")
    assert broken == []
