"""What an office's task is, as facts: the env states them, a trainer turns them into settings.

The paper's office is 17 moves from start to goal, and the registered defaults (every episode from the map's
start, a 300-step time limit) are its task. On another map (a user's own, a generated one) the env states
(:func:`task_facts`) what a trainer needs to know of it, and nothing of any algorithm:

* ``shortest_path``: the fewest moves from the map's start to the goal; ``farthest_start``: the most from any
  cell an episode may start at (the cells reachable from the start);
* ``varying_readings``: whether a cell's readings vary from visit to visit (sensor noise, a recorded database,
  the stand-in robot: :attr:`~twodrl_envs.nomad.core.Robot.varying_readings`); ``on_lattice``: whether the
  robot moves on the lattice (then the ``progress`` option exists);
* ``time_limit``: the map's episode time limit, ``max(300, 3 farthest_start)`` (the paper's 300 on its maps): the
  env's own, as a Gymnasium spec's ``max_episode_steps`` is.

What to do with them is the trainer's (``twodrl_zoo.recipe``): where episodes start (the env's ``starts`` option,
e.g. exploring starts for training), the discount, the budget, the entropy bonus.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.nomad.core import Robot
from twodrl_envs.nomad.geometry import MAPS_DIR
from twodrl_envs.nomad.maps import map_source

PAPER_MAPS = ("office", "open")
"""Shipped maps of the paper's experiment: their task is the registered defaults (:func:`task_facts` gives None)."""
MIN_TIME_LIMIT = 300
"""The paper's time limit (steps), the least a derived one is."""


def is_paper_map(map: str | Path | None) -> bool:
    """Whether ``map`` is one of :data:`PAPER_MAPS` (``None`` is the office)."""
    source = Path(map_source(map))
    return any(source == (MAPS_DIR / f"{name}.json").resolve() for name in PAPER_MAPS)


def task_facts(robot: Robot) -> dict[str, Any] | None:
    """The facts of ``robot``'s task on its map (module docstring); None on the paper's maps.

    :raises ValueError: if the robot cannot reach the goal from the map's start
    """
    office = robot.core.office
    if is_paper_map(office.source):
        return None
    distance = robot.goal_distance
    if not np.isfinite(distance[robot.core.start_cell]):
        raise ValueError(f"map {office.source}: this robot cannot reach the goal from the start (its moves)")
    moves = int(distance[robot.core.start_cell])
    farthest = int(distance[robot.start_cells].max()) if len(robot.start_cells) else moves
    return {
        "map": office.source,
        "shortest_path": moves,
        "farthest_start": farthest,
        "time_limit": max(MIN_TIME_LIMIT, 3 * farthest),
        "varying_readings": bool(robot.varying_readings),
        "on_lattice": bool(robot.on_lattice),
    }
