"""A report of the other form, ``report(rows, specs, out)``: the rows as CSV records (strings), every part's spec."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def report(rows: list[dict[str, str]], specs: list[dict[str, Any]], out: Path) -> str:
    text = f"{len(rows)} rows of {[s['name'] for s in specs]}, arms {sorted({r['arm'] for r in rows})}"
    (out / "table.md").write_text(text + "\n")
    return text
