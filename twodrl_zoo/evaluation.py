"""The one test-episode runner of the commands, both bench protocols and the scripts: deterministic episodes of a
model on a VecEnv (e.g. from a map's start), their returns, lengths, last infos (goal, events) and routes. Needs no
extra."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from sb3_twodrl.callbacks import EpisodeRecord, EpisodeTracker

__all__ = ["Episode", "goal_rate", "run_episodes"]


@dataclass(frozen=True)
class Episode:
    """One finished test episode of :func:`run_episodes`."""

    episode_return: float
    """The rewards the VecEnv returned, summed (normalised where a ``VecNormalize`` normalises them)."""
    length: int
    info: dict[str, Any]
    """The info of its last step (``is_success``, the event counts so far, ...)."""
    record: EpisodeRecord
    """:class:`~sb3_twodrl.callbacks.EpisodeTracker`'s record: the route it took, a collision at any step."""


def run_episodes(model: BaseAlgorithm, env: VecEnv, per_env: int = 1, deterministic: bool = True) -> list[Episode]:
    """The first ``per_env`` episodes of each sub-env of ``env`` from a reset, sub-env by sub-env; deterministic by
    default. Every step is one ``predict`` for the whole batch; a sub-env that has finished its episodes keeps
    stepping (the batch moves together) but counts no more. Seeding ``env`` (``env.seed``) and torch is the
    caller's."""
    n = env.num_envs
    tracker = EpisodeTracker(n)
    returns, lengths = np.zeros(n), np.zeros(n, dtype=np.int64)
    ended: list[list[Episode]] = [[] for _ in range(n)]
    obs = env.reset()
    while any(len(episodes) < per_env for episodes in ended):
        actions, _ = model.predict(obs, deterministic=deterministic)  # type: ignore[arg-type]
        obs, rewards, dones, infos = env.step(actions)
        returns, lengths = returns + rewards, lengths + 1
        finished = np.flatnonzero(dones).tolist()
        for i, record in zip(finished, tracker.step(infos, dones, rewards), strict=True):
            if len(ended[i]) < per_env:
                ended[i].append(Episode(float(returns[i]), int(lengths[i]), infos[i], record))
            returns[i], lengths[i] = 0.0, 0
    return [episode for episodes in ended for episode in episodes]


def goal_rate(episodes: Sequence[Episode]) -> float:
    """The share of ``episodes`` whose last ``info["is_success"]`` is true; NaN if one of them lacks the key."""
    return float(np.mean([float(episode.info.get("is_success", math.nan)) for episode in episodes]))
