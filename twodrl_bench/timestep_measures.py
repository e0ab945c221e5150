"""What a timesteps job measures (:mod:`twodrl_bench.timesteps`): the training episodes its ``Monitor`` files
record, the learning curve over them, the final deterministic evaluation, its env, and the first check at which an
episode reached the goal."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_zoo.evaluation import goal_rate, run_episodes

EVAL_SEED = 10**6
"""Seed of the evaluation env, plus the training seed: apart from the training seeds."""
CURVE_BINS = 20
"""Learning-curve points: training episodes binned by the timestep at which they ended."""


def training_episodes(run_dir: Path, n_envs: int, events: str | None) -> np.ndarray:
    """Every training episode as ``(timestep it ended at, return, punishment events)``, sorted by timestep.

    The Monitor of sub-env ``i`` writes ``<run_dir>/<i>.monitor.csv``; the sub-envs step together,
    so an episode that ends at a sub-env's k-th step ends at timestep ``k * n_envs``.
    """
    rows = []
    for i in range(n_envs):
        with (run_dir / f"{i}.monitor.csv").open() as f:
            next(f)  # the JSON header
            steps = 0
            for record in csv.DictReader(f):
                steps += int(record["l"])
                rows.append((steps * n_envs, float(record["r"]), _number(record[events]) if events else 0.0))
    return np.array(sorted(rows), dtype=np.float64).reshape(-1, 3)


def _number(text: str) -> float:
    """A ``Monitor`` CSV field as a number (a bool info key is written ``True``/``False``)."""
    return {"True": 1.0, "False": 0.0}[text] if text in ("True", "False") else float(text)


def learning_curve(episodes: np.ndarray, n_timesteps: int, bins: int = CURVE_BINS) -> list[list[float]]:
    """Per bin of ``n_timesteps / bins`` steps: ``[end timestep, mean return, events per episode]`` (NaN if empty)."""
    edges = np.linspace(0, n_timesteps, bins + 1)
    index = np.clip(np.searchsorted(edges, episodes[:, 0], side="left") - 1, 0, bins - 1)
    curve = []
    for b in range(bins):
        inside = episodes[index == b]
        mean = inside.mean(axis=0) if len(inside) else np.full(3, math.nan)
        curve.append([float(edges[b + 1]), float(mean[1]), float(mean[2])])
    return curve


def evaluate(model: Any, env: Any, episodes: int, events: str | None) -> dict[str, float]:
    """Mean return, length and punishment events of ``episodes`` deterministic episodes in a row on the one-env
    ``env`` (:func:`twodrl_zoo.evaluation.run_episodes`), the share with an event, the share that reached the
    goal (:func:`twodrl_zoo.evaluation.goal_rate`, NaN where the env does not say) and the reward per step over all
    their steps (paper section 3.4.1)."""
    ran = run_episodes(model, env, per_env=episodes)
    r = np.array([episode.episode_return for episode in ran])
    n = np.array([episode.length for episode in ran])
    e = np.array([float(episode.info.get(events, 0.0)) if events else 0.0 for episode in ran])
    return {
        "final_return": float(r.mean()),
        "final_return_std": float(r.std()),
        "final_length": float(n.mean()),
        "final_events": float(e.mean()),
        "final_event_share": float(np.mean(e > 0)),
        "final_success_share": goal_rate(ran),
        "final_reward_per_step": float(r.sum() / n.sum()),
    }


def eval_env(env: str, entry: dict[str, Any], env_kwargs: dict[str, Any], seed: int, stats: Path | None = None) -> Any:
    """A one-env evaluation VecEnv of ``env`` with ``env_kwargs``, the entry's wrapper, seeded ``seed``; with the
    run's ``VecNormalize`` statistics ``stats`` (frozen) where the entry normalises."""
    from rl_zoo3 import utils as zoo_utils
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    made = make_vec_env(
        env, n_envs=1, seed=seed, wrapper_class=zoo_utils.get_wrapper_class(entry), env_kwargs=env_kwargs
    )
    if stats is not None and stats.exists():
        made = VecNormalize.load(str(stats), made)
        made.training, made.norm_reward = False, False
    return made


def first_goal(checks: list[list[float]]) -> float:
    """The timestep of the first check at which an episode reached the goal, NaN if none did."""
    return next((float(t) for t, share in checks if share > 0), math.nan)
