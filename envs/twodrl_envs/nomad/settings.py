"""Training settings derived from a map: what depends on the office, for offices other than the paper's.

The paper's settings (the packaged hyperparameters: discount 0.9, a 300-step time limit, 1M steps, every episode
from the start) were made for the paper's office, 17 moves from start to goal. On a larger office the goal's
discounted value at the start vanishes (0.9**80 ~ 2e-4) and an episode from the start rarely meets the goal
before the time limit. :func:`map_settings` derives, from the map's lattice distances:

* **exploring starts** for training (``starts="uniform"``: each training episode starts at a cell drawn from the
  cells reachable from the start; Sutton & Barto 2018, sec. 5.3; Kakade & Langford 2002's restart
  distribution): every cell's value is learned from episodes that begin near it, so the goal's value spreads back
  to the start without an episode from the start having to find it first. Test episodes still start at the
  map's start;
* the **reward discount** ``gamma = max(0.9, 1 - 1/L)`` for a shortest path of ``L`` moves: the goal's reward
  discounted over the path keeps about ``e**-1`` of its value at the start (the punishment discount stays the
  paper's short one);
* the **time limit** ``max(300, 3 D)`` steps, ``D`` the most moves from any start cell to the goal;
* the **budget** ``n_timesteps = min(max(1e6, 40,000 L), 2e7)`` (rounded up to 1e5), twice that where a cell's
  readings vary from visit to visit (sensor noise, a recorded database, the stand-in robot: ``Robot.varying_readings``;
  on ``docs/own_office.md``'s example the database env learned in 3 of 4 seeds at 1M steps, in 2 of 2 at 2M);
* on offices longer than 80 moves (size L and beyond), where the value of the goal differs little between
  neighbouring cells far from it (``gamma**d (1 - gamma)``), two more: the **entropy bonus** drops from the
  packaged 0.05 to ``LONG_ENT_COEF`` (the bonus otherwise outweighs those differences and keeps the far policy
  near uniform) and the **progress signal** (``progress=LONG_PROGRESS``, lattice robots; a move closer to the goal
  adds to ``r_R``, one farther to ``r_P``: :class:`~twodrl_envs.nomad.core.LatticeOutcomes`) gives every move a
  signal of its own.

``r_R >= 0`` and ``r_P >= 0`` keep their meaning: nothing here changes an evaluation. The rules were set on the
development maps (``docs/own_office.md``'s example, the shipped ``corridor``, generated map seeds 0-99) before
any held-out map was trained on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.nomad.core import Robot
from twodrl_envs.nomad.geometry import MAPS_DIR, map_source

PAPER_MAPS = ("office", "open")
"""Shipped maps of the paper's experiment: their settings are the paper's (:func:`map_settings` gives None)."""
SIZE_CLASSES = (("S", 30), ("M", 80), ("L", 200))
"""Size class by shortest path: S <= 30 moves, M 31-80, L 81-200; longer is XL."""
LONG_MOVES = 80
"""Shortest paths longer than this (size L and beyond) get the entropy bonus and the progress signal below."""
LONG_ENT_COEF = 0.01
LONG_PROGRESS = 0.05
MEASURED_MOVES = 200
"""The longest shortest path the derived settings were measured on (``docs/own_office.md``); beyond it, a warning."""


def size_class(moves: int) -> str:
    """``"S"``, ``"M"``, ``"L"`` or ``"XL"`` for a shortest path of ``moves`` moves."""
    return next((name for name, most in SIZE_CLASSES if moves <= most), "XL")


def is_paper_map(map: str | Path | None) -> bool:
    """Whether ``map`` is one of :data:`PAPER_MAPS` (``None`` is the office)."""
    source = Path(map_source(map))
    return any(source == (MAPS_DIR / f"{name}.json").resolve() for name in PAPER_MAPS)


@dataclass(frozen=True)
class MapSettings:
    """Settings derived from one map (module docstring): what a training command applies."""

    map: str
    shortest_path: int
    farthest: int
    gamma: float
    max_episode_steps: int
    n_timesteps: int
    ent_coef: float | None = None
    """The entropy bonus where the map needs another than the packaged one, else None."""
    progress: float = 0.0
    """The progress signal's weight (0: none)."""

    @property
    def size(self) -> str:
        """The map's size class (:func:`size_class` of its shortest path)."""
        return size_class(self.shortest_path)

    def hyperparams(self) -> dict[str, Any]:
        """Hyperparameters that replace the packaged ones."""
        hyperparams: dict[str, Any] = {"gamma": self.gamma, "n_timesteps": self.n_timesteps}
        if self.ent_coef is not None:
            hyperparams["ent_coef"] = self.ent_coef
        return hyperparams

    def env_kwargs(self) -> dict[str, Any]:
        """Options of the training envs: exploring starts and the time limit."""
        options: dict[str, Any] = {"starts": "uniform", "max_episode_steps": self.max_episode_steps}
        if self.progress:
            options["progress"] = self.progress
        return options

    def eval_env_kwargs(self) -> dict[str, Any]:
        """Options of the test envs: the map's start, the time limit."""
        return {"starts": "map", "max_episode_steps": self.max_episode_steps}

    def note(self) -> str:
        """What was derived, and a warning where the map is longer than the settings were measured on."""
        text = (
            f"settings derived from the map ({self.size}: shortest path {self.shortest_path} moves, farthest start "
            f"{self.farthest}): gamma {self.gamma}, time limit {self.max_episode_steps} steps, "
            f"{self.n_timesteps:,} steps, training episodes from random reachable cells (exploring starts)"
        )
        if self.ent_coef is not None:
            text += f", entropy bonus {self.ent_coef}"
        if self.progress:
            text += f", progress signal {self.progress}"
        if self.shortest_path > MEASURED_MOVES:
            text += (
                f"; WARNING: the shortest path is longer than the {MEASURED_MOVES} moves these settings were measured "
                "on, they may not learn it in the budget: split the office, or move the start nearer the goal"
            )
        return text


def map_settings(robot: Robot) -> MapSettings | None:
    """The settings derived from ``robot``'s map (module docstring); None on the paper's maps."""
    office = robot.core.office
    if is_paper_map(office.source):
        return None
    distance = robot.goal_distance
    if not np.isfinite(distance[robot.core.start_cell]):
        raise ValueError(f"map {office.source}: this robot cannot reach the goal from the start (its moves)")
    moves = int(distance[robot.core.start_cell])
    farthest = int(distance[robot.start_cells].max()) if len(robot.start_cells) else moves
    budget = min(max(1_000_000, 40_000 * moves), 20_000_000) * (2 if robot.varying_readings else 1)
    return MapSettings(
        map=office.source,
        shortest_path=moves,
        farthest=farthest,
        gamma=round(max(0.9, 1.0 - 1.0 / moves), 3),
        max_episode_steps=max(300, 3 * farthest),
        n_timesteps=int(math.ceil(budget / 100_000) * 100_000),
        ent_coef=LONG_ENT_COEF if moves > LONG_MOVES else None,
        progress=LONG_PROGRESS if moves > LONG_MOVES and robot.on_lattice else 0.0,
    )
