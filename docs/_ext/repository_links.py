"""Sphinx extension: the Markdown pages keep the links that work on a repository browser, and the site serves them.

* The studies' records, every Markdown file under ``results/`` (a study's ``table.md`` and ``preregistration.md``,
  ``MANIFEST.md``), are pages of the site at the same path (``results/<study>/table.md`` is the page
  ``results/<study>/table``): the build copies them into ``docs/results/`` (a folder it keeps in step with
  ``results/``, ignored by git), and a link to a record, or to a study part's folder that has a ``table.md``, goes to
  that page. A record's page is reached by links (no table of contents lists it), titled by its path where it has no
  title.
* A link to any other file of the repository outside ``docs/`` (a ``rows.csv``, a spec, a script) becomes a
  download of that file (MyST's ``path:`` links): the site carries a copy.
* ``<!-- readme: START | END -->`` on a line of its own is replaced by the README's text between the line
  ``START`` and the line ``END`` (both excluded), its links rewritten to resolve from ``docs/``: the install
  and quick-start pages show the README's sections, not a copy of them.

A link to another folder has no page to go to: it is left as it is, and the build warns.
"""

import os
import re
import tempfile
from pathlib import Path

from sphinx.application import Sphinx

LINK = re.compile(r"(!?)\[([^\]]*)\]\(([^)\s]+)\)")
"""A Markdown link or image: the ``!``, the text, the target."""
README_SECTION = re.compile(r"^<!-- readme: (.+?) \| (.+?) -->$", re.MULTILINE)
FENCE = re.compile(r"^(```.*?^```)", re.MULTILINE | re.DOTALL)
RECORDS = "results"
"""The folder of the studies' records, beside ``docs/``; their pages' copies are under the same name in ``docs/``."""
HEADING = re.compile(r"^(#{1,6}) ", re.MULTILINE)


def readme_section(readme: Path, start: str, end: str) -> str:
    """The README's lines strictly between the line ``start`` and the next line ``end``."""
    lines = readme.read_text(encoding="utf-8").splitlines()
    if start not in lines:
        raise ValueError(f"readme: no line {start!r} in {readme}")
    first = lines.index(start) + 1
    if end not in lines[first:]:
        raise ValueError(f"readme: no line {end!r} after {start!r} in {readme}")
    return "\n".join(lines[first : lines.index(end, first)])


def record_page(path: Path, srcdir: Path) -> Path | None:
    """The page of the record at ``path`` (resolved): a Markdown file under the records, or a folder of them that
    has a ``table.md``; None for anything else."""
    records = srcdir.parent / RECORDS
    if records not in path.parents:
        return None
    if path.is_dir() and (path / "table.md").is_file():
        path = path / "table.md"
    if path.suffix != ".md" or not path.is_file():
        return None
    return srcdir / RECORDS / path.relative_to(records)


def rewrite_links(text: str, base: Path, page_dir: Path, srcdir: Path) -> str:
    """``text``'s links, relative to ``base``, made relative to ``page_dir``: a record's goes to its page, another
    repository file outside ``srcdir`` becomes a download, an image stays an image. Links inside code fences,
    external links and anchors are kept."""

    def one(match: re.Match[str]) -> str:
        bang, label, target = match.groups()
        if "://" in target or target.startswith(("#", "mailto:", "path:", "project:")):
            return match[0]
        path, hash_, anchor = target.partition("#")
        resolved = (base / path).resolve()
        if bang:
            return f"![{label}]({os.path.relpath(resolved, page_dir).replace(os.sep, '/')})"
        page = record_page(resolved, srcdir)
        if page is not None:
            resolved = page
        relative = os.path.relpath(resolved, page_dir).replace(os.sep, "/")
        if srcdir in resolved.parents:
            return f"[{label}]({relative}{hash_}{anchor})"
        if resolved.is_file():
            return f"[{label}](path:{relative})"
        return match[0]

    parts = FENCE.split(text)
    return "".join(part if part.startswith("```") else LINK.sub(one, part) for part in parts)


def mirror_records(srcdir: Path) -> list[Path]:
    """Copy every record (Markdown file under the records) to its page's file under ``srcdir`` where the copy
    differs (the build reads again only those; a file is replaced whole, so a build beside this one never reads half
    of it), and remove the copies whose record is gone; the pages' files."""
    records, pages = srcdir.parent / RECORDS, srcdir / RECORDS
    wanted = {pages / path.relative_to(records): path for path in sorted(records.rglob("*.md"))}
    for page in sorted(pages.rglob("*.md")) if pages.is_dir() else ():
        if page not in wanted:
            page.unlink(missing_ok=True)
    for page, record in wanted.items():
        text = record.read_bytes()
        if not page.is_file() or page.read_bytes() != text:
            page.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile(dir=page.parent, delete=False) as part:
                part.write(text)
            os.replace(part.name, page)
    return sorted(wanted)


def consecutive_headings(text: str) -> str:
    """``text`` with each heading at most one level below the one before it (a record's ``###`` under its title
    becomes ``##``); code fences are kept."""
    level = 0

    def one(match: re.Match[str]) -> str:
        nonlocal level
        level = min(len(match[1]), level + 1)
        return "#" * level + " "

    parts = FENCE.split(text)
    return "".join(part if part.startswith("```") else HEADING.sub(one, part) for part in parts)


def record_source(text: str, docname: str, srcdir: Path) -> str:
    """A record's page: marked as reached by links (no table of contents lists it), titled by its path where it
    has no title, its headings made consecutive, its links resolved from the record's folder."""
    page_dir = (srcdir / docname).parent
    text = rewrite_links(text, srcdir.parent / Path(docname).parent, page_dir, srcdir)
    if not text.startswith("# "):
        text = f"# {docname}.md\n\n{text}"
    return f"---\norphan: true\n---\n\n{consecutive_headings(text)}"


def on_builder_inited(app: Sphinx) -> None:
    """Bring the records' pages in step with the records before the build looks for pages."""
    mirror_records(Path(app.srcdir).resolve())


def on_source_read(app: Sphinx, docname: str, source: list[str]) -> None:
    """Fill a page's README sections, then rewrite its links to repository files; a record's page its own way."""
    srcdir = Path(app.srcdir).resolve()
    if docname.startswith(f"{RECORDS}/"):
        source[0] = record_source(source[0], docname, srcdir)
        return
    page_dir = (srcdir / docname).parent
    readme = srcdir.parent / "README.md"

    def section(match: re.Match[str]) -> str:
        return rewrite_links(readme_section(readme, match[1], match[2]), readme.parent, page_dir, srcdir)

    text = README_SECTION.sub(section, source[0])
    source[0] = rewrite_links(text, page_dir, page_dir, srcdir)


def setup(app: Sphinx) -> dict[str, bool]:
    """Register the ``builder-inited`` and ``source-read`` handlers."""
    app.connect("builder-inited", on_builder_inited)
    app.connect("source-read", on_source_read)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
