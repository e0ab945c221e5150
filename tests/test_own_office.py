"""``docs/own_office.md`` run as written: its map, its check, its database, its training commands learn (goal rate
>= 0.8 from the map's start), its replay.

The map is the doc's JSON block; the commands are its ``$`` lines from steps 2-4 that succeed (the two error
examples name files the doc does not give), run in order from an empty folder.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "own_office.md"


def doc_commands() -> list[str]:
    """The doc's ``$`` commands of steps 2-4, in order, without the two error examples."""
    text = DOC.read_text()
    steps = text[text.index("## 2. Check it") : text.index("## 5. ")]
    commands = [line[2:] for line in steps.splitlines() if line.startswith("$ sb3-twodrl-")]
    return [c for c in commands if "narrow_door" not in c and "my_offce" not in c]


def test_the_doc_has_its_commands() -> None:
    commands = doc_commands()
    assert [c.split()[0] for c in commands] == [
        "sb3-twodrl-record-database",
        "sb3-twodrl-record-database",
        "sb3-twodrl-train",
        "sb3-twodrl-enjoy",
        "sb3-twodrl-train",
    ]


@pytest.mark.slow
def test_the_doc_run_as_written_learns_its_office(tmp_path: Path) -> None:
    text = DOC.read_text()
    (tmp_path / "my_office.json").write_text(text.split("```json\n", 1)[1].split("```", 1)[0])
    rates = []
    for command in doc_commands():
        out = subprocess.run(["bash", "-c", command], cwd=tmp_path, capture_output=True, text=True, timeout=900)
        assert out.returncode == 0, (command, out.stdout[-2000:], out.stderr[-3000:])
        rates += [float(r) for r in re.findall(r"^sb3-twodrl-train: goal rate ([0-9.]+)", out.stdout, re.MULTILINE)]
        rates += [float(r) / 100 for r in re.findall(r"^Success rate: ([0-9.]+)%", out.stdout, re.MULTILINE)]
    assert len(rates) == 3 and min(rates) >= 0.8, rates  # both trainings' goal rates, the replay's from the start
