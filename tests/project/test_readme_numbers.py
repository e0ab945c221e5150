"""Every result the README quotes in "When to use it" and "Results" is in a committed table that the same paragraph
or table row links (issue 53): a number changed in the README, or one that no linked table has, fails."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
SECTIONS = ("When to use it", "Results")
METHOD = {"95%", "80%"}
"""Settings of the method, not results: the intervals' level and the office's learned rule."""
# a number standing alone: a decimal, a count k/n or a percentage (A2C, 50k, 1M and ent0.05 are not numbers here)
NUMBER = re.compile(r"(?<![\w.])[+-]?\d+(?:\.\d+)?(?:/\d+)?%?(?![\w.])")
# a number anywhere in a table, arm names included (ent0.05, auto0.98)
TABLE_NUMBER = re.compile(r"[+-]?\d+(?:\.\d+)?(?:/\d+)?%?")
# an estimate with its interval, "+0.193 [+0.064, +0.323]" or "7/10 [0.40, 0.89]": quoted and matched as one
_VALUE = r"[+-]?\d+(?:\.\d+)?(?:/\d+)?"
INTERVAL = re.compile(rf"(?<![\w.])({_VALUE}) \[({_VALUE}), ({_VALUE})\]")
LINK = re.compile(r"\]\(([^)\s]+)\)")


def section(text: str, title: str) -> str:
    """The text of the ``## {title}...`` section up to the next ``## `` heading."""
    match = re.search(rf"^## {re.escape(title)}\b.*?$(.*?)(?=^## |\Z)", text, flags=re.MULTILINE | re.DOTALL)
    if match is None:
        raise ValueError(f"README has no section {title!r}")
    return match.group(1)


def blocks(text: str) -> list[str]:
    """Paragraphs, and each row of a table on its own."""
    out = []
    for paragraph in re.split(r"\n\s*\n", text):
        lines = paragraph.strip().splitlines()
        if lines and lines[0].startswith("|"):
            out += lines
        elif lines:
            out.append(paragraph)
    return out


def quoted(block: str) -> list[str]:
    """The results a block quotes outside its links: each estimate with its interval, then each other decimal,
    count and percentage (integers such as seeds, epochs and step budgets are settings)."""
    words = re.sub(r"\s+", " ", LINK.sub("]", block))
    intervals = [match.group(0) for match in INTERVAL.finditer(words)]
    rest = INTERVAL.sub(" ", words)
    return intervals + [n for n in NUMBER.findall(rest) if re.search(r"[./%]", n) and n not in METHOD]


def key(number: str) -> str | float | tuple[str | float, ...]:
    """What two spellings of one result share: the value of a decimal (0.8 is 0.800), the text of a count, the
    three of an estimate with its interval."""
    match = INTERVAL.fullmatch(number)
    if match:
        return tuple(key(part) for part in match.groups())
    return number.lstrip("+") if "/" in number or "%" in number else float(number)


def held(table: Path) -> set[str | float | tuple[str | float, ...]]:
    """Every number of ``table`` and every estimate with its interval."""
    text = re.sub(r"\s+", " ", table.read_text())
    return {key(n) for n in TABLE_NUMBER.findall(text)} | {key(m.group(0)) for m in INTERVAL.finditer(text)}


def unmatched(readme: str) -> list[str]:
    """Each quoted number that no table its block links holds, with the block's tables."""
    problems = []
    for title in SECTIONS:
        for block in blocks(section(readme, title)):
            numbers = quoted(block)
            tables = [ROOT / t for t in LINK.findall(block) if t.startswith("results/") and t.endswith(".md")]
            if numbers and not tables:
                problems.append(f"{numbers} quoted without a link to a results table: {block[:80]!r}")
                continue
            known = set().union(*(held(t) for t in tables))
            names = [t.relative_to(ROOT).as_posix() for t in tables]
            problems += [f"{n} not in {names}" for n in numbers if key(n) not in known]
    return problems


def test_every_number_the_readme_quotes_is_in_the_table_it_links() -> None:
    readme = README.read_text()
    assert sum(len(quoted(b)) for title in SECTIONS for b in blocks(section(readme, title))) >= 25
    assert unmatched(readme) == []


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("-0.041 [-0.078, -0.005]", "-0.041 [-0.078, -0.004]"),  # one digit of an interval
        ("7/10 [0.40, 0.89]", "7/10 [0.40, 0.90]"),
        ("| 36/40; 32/40 |", "| 36/40; 33/40 |"),
        ("+0.0020 [+0.0006, +0.0034]", "+0.0020 [+0.0006, +0.0035]"),
        ("| -7.9; 0.875 |", "| +7.9; 0.875 |"),  # the sign
        ("0.94 [0.91, 0.97]", "0.94 [0.91, 0.98]"),
        ("| 0.494 |", "| 49.4% |"),  # a percentage no table has
    ],
)
def test_a_changed_number_fails(old: str, new: str) -> None:
    readme = README.read_text()
    assert old in readme
    assert unmatched(readme.replace(old, new)) != []


def test_a_number_without_a_linked_table_fails() -> None:
    readme = README.read_text()
    block = "[factorial](results/factorial/table.md)"
    assert block in readme
    assert any("without a link" in p for p in unmatched(readme.replace(block, "factorial")))
