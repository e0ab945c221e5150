"""Test trials: one episode in each sub-env of a test VecEnv, every step one batched ``predict``."""

from __future__ import annotations

import random
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from sb3_twodrl.callbacks import EpisodeRecord, EpisodeTracker, summarize_episodes
from twodrl_bench.protocol import ROUTES


def run_test_trials(model: BaseAlgorithm, test_env: VecEnv, seed: int, deterministic: bool = False) -> dict[str, float]:
    """Metrics (:func:`~sb3_twodrl.callbacks.summarize_episodes`, a share for each of :data:`~.protocol.ROUTES`)
    of one trial per sub-env of ``test_env``.

    Sub-env ``i`` is reset with seed ``seed + i``; the policy samples with torch, numpy and Python
    generators seeded by ``seed``, and the caller's generator states are restored afterwards, so a
    test never perturbs the learning run. A sub-env that finished its trial keeps stepping (the
    batch moves together) but is not counted again.
    """
    n = test_env.num_envs
    np_state, py_state = np.random.get_state(), random.getstate()
    try:
        with th.random.fork_rng(devices=[]):
            th.manual_seed(seed)
            np.random.seed(seed % 2**32)
            random.seed(seed)
            test_env.seed(seed)
            obs = test_env.reset()
            tracker = EpisodeTracker(n)
            records: list[EpisodeRecord | None] = [None] * n
            while any(r is None for r in records):
                actions, _ = model.predict(obs, deterministic=deterministic)
                obs, rewards, dones, infos = test_env.step(actions)
                ended = np.flatnonzero(dones).tolist()
                for i, record in zip(ended, tracker.step(infos, dones, rewards), strict=True):
                    if records[i] is None:
                        records[i] = record
    finally:
        np.random.set_state(np_state)
        random.setstate(py_state)
    return summarize_episodes((r for r in records if r is not None), ROUTES)


def trial_outcomes(model: BaseAlgorithm, test_env: VecEnv, seed: int, deterministic: bool = True) -> list[str]:
    """The outcome of one trial per sub-env of ``test_env``, in sub-env order (sub-env ``i`` seeded ``seed + i``).

    ``"shortcut"`` or ``"detour"`` (the goal, by that route), ``"goal"`` (the goal, no route label),
    ``"collision"`` or ``"timeout"``.
    """
    n = test_env.num_envs
    with th.random.fork_rng(devices=[]):
        th.manual_seed(seed)
        test_env.seed(seed)
        obs = test_env.reset()
        ends: list[dict[str, Any] | None] = [None] * n
        while any(o is None for o in ends):
            actions, _ = model.predict(obs, deterministic=deterministic)
            obs, _, dones, infos = test_env.step(actions)
            for i in np.flatnonzero(dones):
                if ends[i] is None:
                    ends[i] = infos[i]
    outcomes = []
    for info in ends:  # every trial has ended
        if info.get("is_success"):
            outcomes.append(info["route"] if info.get("route") in ROUTES else "goal")
        else:
            outcomes.append("collision" if info.get("collision") else "timeout")
    return outcomes


def tally(outcomes: list[str]) -> dict[str, int]:
    """Counts of successes, shortcut successes, collisions and time-outs among ``outcomes`` (transfer tables)."""
    return {
        "success": sum(o in (*ROUTES, "goal") for o in outcomes),
        "shortcut": outcomes.count("shortcut"),
        "collision": outcomes.count("collision"),
        "timeout": outcomes.count("timeout"),
    }
