"""A policy's trials on both stand-in robots, side by side: the artifact model (``NomadOfficeReal-v0``) and the
physics engine (``NomadOfficeMuJoCo-v0``, extra ``sb3-twodrl[mujoco]``), by the transfer trials' own loop
(:func:`twodrl_bench.trials.trial_outcomes`, deterministic, from the map's start, sub-env ``i`` seeded
``seed + i``)."""

from __future__ import annotations

from typing import Any

from stable_baselines3.common.base_class import BaseAlgorithm

from twodrl_bench.trials import env_outcomes, tally

STAND_INS = ("NomadOfficeMuJoCo-v0", "NomadOfficeReal-v0")
"""The stand-in robots' env IDs: physics first, then the artifact model."""


def stand_in_trials(
    model: BaseAlgorithm, n: int, seed: int = 0, env_kwargs: dict[str, Any] | None = None
) -> dict[str, dict[str, int]]:
    """Counts of ``n`` deterministic trials of ``model`` on each of :data:`STAND_INS` (``env_kwargs``, e.g. the
    map, to both, with the test settings the env derives from them): ``{env_id: {"success", "shortcut",
    "collision", "timeout"}}`` (:func:`~twodrl_bench.trials.tally`).

    :raises ValueError: if ``n`` is not a positive int
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"n must be a positive int, got {n!r}")
    from twodrl_zoo.zoo import import_gym_packages

    import_gym_packages()  # the env packages that register the IDs
    return {env_id: tally(env_outcomes(model, env_id, n, seed, dict(env_kwargs or {}))) for env_id in STAND_INS}


ROBOT_COLUMNS = {"NomadOfficeMuJoCo-v0": "mujoco", "NomadOfficeReal-v0": "real"}
"""The column prefix of each stand-in robot in a row."""


def stand_in_columns(counts: dict[str, dict[str, int]]) -> dict[str, int]:
    """A row's columns of :func:`stand_in_trials`' counts: ``mujoco_success``, ``real_collision``, ..."""
    return {f"{ROBOT_COLUMNS[env_id]}_{outcome}": n for env_id, tally in counts.items() for outcome, n in tally.items()}
