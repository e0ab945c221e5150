"""Training settings from a task's facts: the one rule, for offices other than the paper's.

The packaged settings (discount 0.9, 1M steps) were made for the paper's office, 17 moves from start to goal. On a
larger office the goal's discounted value at the start vanishes (0.9**80 ~ 2e-4). An env that states its task's
facts (a class method ``task_facts(**options)``, e.g. :func:`twodrl_envs.nomad.task.task_facts`: shortest path
``L``, farthest start ``D``, its time limit, whether readings vary) gets from :func:`derive`:

* its **episode options** (the env's ``starts`` and ``max_episode_steps``): training episodes from random
  reachable cells (``starts="uniform"``, exploring starts: Sutton & Barto 2018, sec. 5.3), tests from the map's
  start (``starts="map"``), both with the map's time limit;
* the **reward discount** ``gamma = max(0.9, 1 - 1/L)``: the goal's reward discounted over the path keeps about
  ``e**-1`` of its value at the start (the punishment discount stays the paper's short one);
* the **budget** ``n_timesteps = min(max(1e6, 40,000 L), 2e7)`` (rounded up to 1e5), twice that where a cell's
  readings vary from visit to visit (on ``docs/own_office.md``'s example the database env learned in 3 of 4 seeds
  at 1M steps, in 2 of 2 at 2M). With goal checks that stop training once the policy has learned
  (``sb3-twodrl-train``: :mod:`twodrl_zoo.manager`) the ceiling is :data:`twodrl_zoo.manager.CEILING` times the
  budget;
* on the lattice, the **progress signal** :data:`PROGRESS` (the env option ``progress``: a move closer to the goal
  adds to ``r_R``, one farther to ``r_P``; potential-based shaping, Ng, Harada and Russell 1999, so the optimal
  policies stay those of the task) gives every move a signal of its own, where the goal's value differs little
  between neighbouring cells far from it (``gamma**d (1 - gamma)``). Revision 1 gave it to offices longer than
  :data:`LONG_MOVES` moves only; revision 2 to every size (``results/every_office``);
* on offices longer than :data:`LONG_MOVES` moves (size L and beyond): the **entropy bonus** drops from the
  packaged 0.05 to :data:`LONG_ENT_COEF` (the bonus otherwise outweighs those differences and keeps the far policy
  near uniform);
* where readings vary (revision 2): **goal checks of** :data:`VARYING_CHECK_EPISODES` **episodes**, as many as the
  train command's final test, so that a check that stops training and the final test read the same noise
  (5 deterministic episodes from the start are one episode repeated on exact readings, but not on varying ones).

``r_R >= 0`` and ``r_P >= 0`` keep their meaning: nothing here changes an evaluation. The rules were set on the
development maps (``docs/own_office.md``'s example, the shipped ``corridor``, generated map seeds 0-99) before any
held-out map was trained on. :data:`REVISION` is the rule the train command uses; a study states the one it ran
with (the bench's committed studies: revision 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

SIZE_CLASSES = (("S", 30), ("M", 80), ("L", 200))
"""Size class by shortest path: S <= 30 moves, M 31-80, L 81-200; longer is XL."""
LONG_MOVES = 80
"""Shortest paths longer than this (size L and beyond) get the entropy bonus and the progress signal below."""
LONG_ENT_COEF = 0.01
PROGRESS = 0.05
"""The progress signal's size: a move closer to the goal adds it to ``r_R`` (the goal's reward is 5)."""
VARYING_CHECK_EPISODES = 20
"""Episodes of a goal check where readings vary (revision 2)."""
REVISION = 2
"""The revision of the rule :func:`derive` applies by default (module docstring); 1 is the rule before."""
REVISIONS = (1, 2)
MEASURED_MOVES = 200
"""The longest shortest path the rule was measured on (``docs/own_office.md``); beyond it, a warning."""


def size_class(moves: int) -> str:
    """``"S"``, ``"M"``, ``"L"`` or ``"XL"`` for a shortest path of ``moves`` moves."""
    return next((name for name, most in SIZE_CLASSES if moves <= most), "XL")


@dataclass(frozen=True)
class Derived:
    """What :func:`derive` gives: hyperparameters over the packaged ones, training and test env options, a note."""

    hyperparams: dict[str, Any] = field(default_factory=dict)
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    eval_env_kwargs: dict[str, Any] = field(default_factory=dict)
    note: str = ""
    check_episodes: int | None = None
    """Episodes per goal check, where the rule sets them (None: the trainer's own)."""


def derive(facts: dict[str, Any], revision: int = REVISION) -> Derived:
    """The settings of a task with ``facts`` by the rule's ``revision`` (module docstring).

    :raises ValueError: if a fact the rule reads is missing or not a positive number of moves, or if ``revision``
        is not one of :data:`REVISIONS`
    """
    if revision not in REVISIONS:
        raise ValueError(f"revision must be one of {REVISIONS}, got {revision!r}")
    for key in ("shortest_path", "farthest_start", "time_limit"):
        if not isinstance(facts.get(key), int) or facts[key] < 1:
            raise ValueError(f"task facts: {key} must be a positive number of moves, got {facts.get(key)!r}")
    moves, limit = facts["shortest_path"], facts["time_limit"]
    budget = min(max(1_000_000, 40_000 * moves), 20_000_000) * (2 if facts.get("varying_readings") else 1)
    hyperparams: dict[str, Any] = {
        "gamma": round(max(0.9, 1.0 - 1.0 / moves), 3),
        "n_timesteps": int(math.ceil(budget / 100_000) * 100_000),
    }
    env_kwargs: dict[str, Any] = {"starts": "uniform", "max_episode_steps": limit}
    if moves > LONG_MOVES:
        hyperparams["ent_coef"] = LONG_ENT_COEF
    if facts.get("on_lattice") and (moves > LONG_MOVES or revision >= 2):
        env_kwargs["progress"] = PROGRESS
    varying = revision >= 2 and bool(facts.get("varying_readings"))
    check_episodes = VARYING_CHECK_EPISODES if varying else None
    eval_env_kwargs = {"starts": "map", "max_episode_steps": limit}
    note = (
        f"settings derived from the map ({size_class(moves)}: shortest path {moves} moves, farthest start "
        f"{facts['farthest_start']}): gamma {hyperparams['gamma']}, time limit "
        f"{limit} steps, budget {hyperparams['n_timesteps']:,} steps, training "
        "episodes from random reachable cells (exploring starts)"
    )
    if "ent_coef" in hyperparams:
        note += f", entropy bonus {hyperparams['ent_coef']}"
    if "progress" in env_kwargs:
        note += f", progress signal {env_kwargs['progress']}"
    if check_episodes is not None:
        note += f", goal checks of {check_episodes} episodes (readings vary)"
    if moves > MEASURED_MOVES:
        note += (
            f"; WARNING: the shortest path is longer than the {MEASURED_MOVES} moves these settings were measured "
            "on, they may not learn it in the budget: split the office, or move the start nearer the goal"
        )
    return Derived(hyperparams, env_kwargs, eval_env_kwargs, note, check_episodes)
