"""Sphinx extension: the Markdown pages keep the links that work on a repository browser, and the site serves them.

* A link from a page to a file of the repository outside ``docs/`` (a study's ``table.md``, a ``rows.csv``, a
  script) becomes a download of that file (MyST's ``path:`` links): the site carries a copy.
* ``<!-- readme: START | END -->`` on a line of its own is replaced by the README's text between the line
  ``START`` and the line ``END`` (both excluded), its links rewritten to resolve from ``docs/``: the install
  and quick-start pages show the README's sections, not a copy of them.

A link to a folder has no page to go to: it is left as it is, and the build warns.
"""

import os
import re
from pathlib import Path

from sphinx.application import Sphinx

LINK = re.compile(r"(!?)\[([^\]]*)\]\(([^)\s]+)\)")
"""A Markdown link or image: the ``!``, the text, the target."""
README_SECTION = re.compile(r"^<!-- readme: (.+?) \| (.+?) -->$", re.MULTILINE)
FENCE = re.compile(r"^(```.*?^```)", re.MULTILINE | re.DOTALL)


def readme_section(readme: Path, start: str, end: str) -> str:
    """The README's lines strictly between the line ``start`` and the next line ``end``."""
    lines = readme.read_text(encoding="utf-8").splitlines()
    if start not in lines:
        raise ValueError(f"readme: no line {start!r} in {readme}")
    first = lines.index(start) + 1
    if end not in lines[first:]:
        raise ValueError(f"readme: no line {end!r} after {start!r} in {readme}")
    return "\n".join(lines[first : lines.index(end, first)])


def rewrite_links(text: str, base: Path, page_dir: Path, srcdir: Path) -> str:
    """``text``'s links, relative to ``base``, made relative to ``page_dir``; repository files outside ``srcdir``
    become downloads. Links inside code fences, external links, anchors and images are kept."""

    def one(match: re.Match[str]) -> str:
        bang, label, target = match.groups()
        if bang or "://" in target or target.startswith(("#", "mailto:", "path:", "project:")):
            return match[0]
        path, hash_, anchor = target.partition("#")
        resolved = (base / path).resolve()
        relative = os.path.relpath(resolved, page_dir).replace(os.sep, "/")
        if srcdir in resolved.parents:
            return f"[{label}]({relative}{hash_}{anchor})"
        if resolved.is_file():
            return f"[{label}](path:{relative})"
        return match[0]

    parts = FENCE.split(text)
    return "".join(part if part.startswith("```") else LINK.sub(one, part) for part in parts)


def on_source_read(app: Sphinx, docname: str, source: list[str]) -> None:
    """Fill a page's README sections, then rewrite its links to repository files."""
    srcdir = Path(app.srcdir).resolve()
    page_dir = (srcdir / docname).parent
    readme = srcdir.parent / "README.md"

    def section(match: re.Match[str]) -> str:
        return rewrite_links(readme_section(readme, match[1], match[2]), readme.parent, page_dir, srcdir)

    text = README_SECTION.sub(section, source[0])
    source[0] = rewrite_links(text, page_dir, page_dir, srcdir)


def setup(app: Sphinx) -> dict[str, bool]:
    """Register the ``source-read`` handler."""
    app.connect("source-read", on_source_read)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
