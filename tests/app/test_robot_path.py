"""``docs/robot_path.md`` run as written on a small office: survey the MuJoCo robot into a bag, import the bag,
train on the database, export the kept policy by the line the training printed, replay the bag through it
offline, then drive the MuJoCo robot with the doc's loop from the start.

The doc walks the paper's office; a map file of one's own "goes in the same place", so the test puts a generated
small office (``sb3-twodrl-map --seed 0 --size S``, a development seed) where the doc names ``office``. The
commands are the doc's ``$`` lines but the import by ``/odom`` (its error example), in the doc's order, the export
moved before the replay as step 4 says ("export the kept policy, step 5's export line, then play the bag").
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers.doc_run import run_doc_commands

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "robot_path.md"
MAP = "my_office.json"


def on_map(text: str) -> str:
    """``text`` with the doc's paper office replaced by the map file ``MAP``."""
    return (
        text.replace("--map office", f"--map {MAP}")
        .replace("""map:'"office"'""", f"""map:'"{MAP}"'""")
        .replace('map="office"', f'map="{MAP}"')
    )


def doc_commands() -> list[str]:
    """The doc's ``$`` commands, but its ``/odom`` import (an error example), on ``MAP``, export before replay."""
    commands = [line[2:] for line in DOC.read_text().splitlines() if line.startswith("$ sb3-twodrl-")]
    commands = [on_map(c) for c in commands if "office_odom.npz" not in c]
    replay = next(c for c in commands if c.startswith("sb3-twodrl-replay-bag"))
    commands.remove(replay)
    return [*commands, replay]


def robot_loop() -> str:
    """Step 5's python block (the drive on the MuJoCo robot), on ``MAP``."""
    text = DOC.read_text()
    return on_map(text[text.index("## 5. ") :].split("```python\n", 1)[1].split("```", 1)[0])


def test_the_doc_has_its_commands() -> None:
    assert [c.split()[0] for c in doc_commands()] == [
        "sb3-twodrl-survey",
        "sb3-twodrl-record-database",
        "sb3-twodrl-train",
        "sb3-twodrl-export",
        "sb3-twodrl-replay-bag",
    ]
    assert "office" not in " ".join(doc_commands()).replace("_office", "").replace("office_", "")
    assert f'map="{MAP}"' in robot_loop() and "robot.time_limit" in robot_loop()


@pytest.mark.slow
def test_the_doc_run_as_written_drives_the_mujoco_robot_to_the_goal(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    pytest.importorskip("rosbags")
    pytest.importorskip("onnxruntime")
    made = subprocess.run(
        f"sb3-twodrl-map --seed 0 --size S --out {MAP}", shell=True, cwd=tmp_path, capture_output=True, text=True
    )
    assert made.returncode == 0, made.stderr[-2000:]
    outputs = run_doc_commands(doc_commands(), tmp_path)
    assert re.search(r"^wrote office_bag_replayed: \d+ messages copied, \d+ moves", outputs[-1], re.MULTILINE)
    loop = subprocess.run([sys.executable, "-c", robot_loop()], cwd=tmp_path, capture_output=True, text=True)
    assert loop.returncode == 0, loop.stderr[-3000:]
    rate = re.search(r"^goal rate on the MuJoCo robot: ([0-9.]+)", loop.stdout, re.MULTILINE)
    assert rate is not None and float(rate.group(1)) >= 0.8, loop.stdout
