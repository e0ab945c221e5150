"""``docs/own_office.md`` run as written: its map, its check, its database, its training commands learn (goal rate
>= 0.8 from the map's start), its replay from the start, its export, and its robot-side loop on the stand-in robot.

The map is the doc's JSON block; the commands are its ``$`` lines from steps 2-5 that succeed (the two error
examples name files the doc does not give), then its robot-side loop (step 5's python block), run in order from
an empty folder.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers.doc_run import run_doc_commands

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "own_office.md"


def doc_commands() -> list[str]:
    """The doc's ``$`` commands of steps 2-5, in order, without the two error examples."""
    text = DOC.read_text()
    steps = text[text.index("## 2. Check it") : text.index("## Start from a generated office")]
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
        "sb3-twodrl-export",
    ]


def robot_loop() -> str:
    """Step 5's python block: the robot-side loop."""
    text = DOC.read_text()
    step = text[text.index("## 5. ") : text.index("## Start from a generated office")]
    return step.split("```python\n", 1)[1].split("```", 1)[0]


@pytest.mark.slow
def test_the_doc_run_as_written_learns_its_office(tmp_path: Path) -> None:
    text = DOC.read_text()
    (tmp_path / "my_office.json").write_text(text.split("```json\n", 1)[1].split("```", 1)[0])
    rates: list[float] = []
    commands = doc_commands()
    for command, stdout in zip(commands, run_doc_commands(commands, tmp_path, timeout=900), strict=True):
        rates += [float(r) for r in re.findall(r"^sb3-twodrl-train: goal rate ([0-9.]+)", stdout, re.MULTILINE)]
        if command.startswith("sb3-twodrl-enjoy"):  # the replay's own line (training prints its checks' too)
            rates += [float(r) / 100 for r in re.findall(r"^Success rate: ([0-9.]+)%", stdout, re.MULTILINE)]
    loop = subprocess.run([sys.executable, "-c", robot_loop()], cwd=tmp_path, capture_output=True, text=True)
    assert loop.returncode == 0, loop.stderr[-3000:]
    rates += [float(r) for r in re.findall(r"^goal rate on the stand-in robot: ([0-9.]+)", loop.stdout, re.MULTILINE)]
    # both trainings' goal rates, the replay's from the start, the exported policy's on the stand-in robot
    assert len(rates) == 4 and min(rates) >= 0.8, rates
