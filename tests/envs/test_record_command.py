"""``sb3-twodrl-record-database``: its help is plain text, and its map check tells lattice points inside obstacles
from free cells walled off from the start."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from twodrl_envs.analysis.cli import describe_map, in_obstacles
from twodrl_envs.nomad.core import office_core


def test_the_help_is_plain_text() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "twodrl_envs.analysis.cli", "--help"], capture_output=True, text=True, check=True
    ).stdout
    assert "--from-bag" in out and "--from-csv" in out
    for markup in ("``", ":func:", ":mod:", ":class:", ":meth:"):
        assert markup not in out


def _room_with_a_table_and_a_closet(tmp_path: Path) -> str:
    """A 4 x 3 m room: a 90 x 90 cm table (its middle is a lattice point), a closed 1 x 1 m closet."""
    outline = [[0, 0, 400, 0], [400, 0, 400, 300], [400, 300, 0, 300], [0, 300, 0, 0]]
    closet = [[300, 200, 300, 300], [300, 200, 400, 200]]
    data = {
        "name": "table-and-closet",
        "bounds": [0, 0, 400, 300],
        "walls": [*outline, *closet],
        "obstacles": [[[40, 180], [130, 180], [130, 270], [40, 270]]],
        "start": [230, 60],
        "regions": {"goal": [0, 0, 100, 100]},
    }
    path = tmp_path / "room.json"
    path.write_text(json.dumps(data))
    return str(path)


def test_the_check_tells_obstacles_from_walled_off_cells(tmp_path: Path) -> None:
    core = office_core(_room_with_a_table_and_a_closet(tmp_path))
    inside = in_obstacles(core)
    xy = core.lattice.cells
    assert inside.sum() > 0 and ((xy[inside] > (40, 180)) & (xy[inside] < (130, 270))).all()
    closet = (xy[:, 0] > 300) & (xy[:, 1] > 200)
    assert closet.sum() > 0 and not core.lattice.reachable[closet].any()
    free, reachable = int((~inside).sum()), int((core.lattice.reachable & ~inside).sum())
    assert free - reachable == int(closet.sum())  # the cells walled off are the closet's, not the table's
    text = describe_map(core)
    expected = (
        f"{free} free lattice cells, {reachable} reachable from the start ({int(closet.sum())} walled off from it); "
        f"{int(inside.sum())} more lattice points lie inside obstacles"
    )
    assert expected in text


def test_the_check_of_the_office_is_unchanged() -> None:
    assert "340 free lattice cells, 340 reachable from the start\n" in describe_map(office_core("office"))
