"""Test trials: one episode in each sub-env of a test VecEnv, every step one batched ``predict``; a policy's
transfer trials on another env (paper section 3.5)."""

from __future__ import annotations

import random
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from sb3_twodrl.callbacks import summarize_episodes
from twodrl_bench.protocol import PAPER_TRIALS, ROUTES, TRANSFER_SEED
from twodrl_bench.settings import test_env_kwargs
from twodrl_zoo.evaluation import Episode, run_episodes

OWN_TRIALS = 10
"""Trials of a transferred policy in its own training env (did it learn at all?)."""


def seeded_trials(model: BaseAlgorithm, test_env: VecEnv, seed: int, deterministic: bool = True) -> list[Episode]:
    """One trial per sub-env of ``test_env`` (:func:`twodrl_zoo.evaluation.run_episodes`), in sub-env order:
    sub-env ``i`` reset with seed ``seed + i``, the policy sampling with torch seeded by ``seed`` in a forked
    generator (the caller's torch state untouched)."""
    with th.random.fork_rng(devices=[]):
        th.manual_seed(seed)
        test_env.seed(seed)
        return run_episodes(model, test_env, deterministic=deterministic)


def run_test_trials(model: BaseAlgorithm, test_env: VecEnv, seed: int, deterministic: bool = False) -> dict[str, float]:
    """Metrics (:func:`~sb3_twodrl.callbacks.summarize_episodes`, a share for each of :data:`~.protocol.ROUTES`)
    of one trial per sub-env of ``test_env`` (:func:`seeded_trials`).

    The numpy and Python generators are seeded by ``seed`` too and the caller's states restored afterwards, so a
    test never perturbs the learning run.
    """
    np_state, py_state = np.random.get_state(), random.getstate()
    try:
        np.random.seed(seed % 2**32)
        random.seed(seed)
        episodes = seeded_trials(model, test_env, seed, deterministic)
    finally:
        np.random.set_state(np_state)
        random.setstate(py_state)
    return summarize_episodes((episode.record for episode in episodes), ROUTES)


def trial_outcomes(model: BaseAlgorithm, test_env: VecEnv, seed: int, deterministic: bool = True) -> list[str]:
    """The outcome of one trial per sub-env of ``test_env`` (:func:`seeded_trials`), in sub-env order.

    ``"shortcut"`` or ``"detour"`` (the goal, by that route), ``"goal"`` (the goal, no route label),
    ``"collision"`` or ``"timeout"``.
    """
    outcomes = []
    for info in (episode.info for episode in seeded_trials(model, test_env, seed, deterministic)):
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


def env_outcomes(model: BaseAlgorithm, env_id: str, n: int, seed: int, env_kwargs: dict[str, Any]) -> list[str]:
    """Outcomes of ``n`` deterministic trials on ``env_id`` (sub-env ``i`` seeded ``seed + i``), with the test
    settings the env derives from ``env_kwargs`` (:func:`twodrl_bench.settings.test_env_kwargs`)."""
    from twodrl_zoo.vec_env import make_test_env

    env = make_test_env(env_id, n, env_kwargs=test_env_kwargs(env_id, env_kwargs))
    try:
        return trial_outcomes(model, env, seed)
    finally:
        env.close()


def transfer_columns(
    model: BaseAlgorithm, env: str, env_kwargs: dict[str, Any], transfer: dict[str, Any]
) -> dict[str, Any]:
    """Paper section 3.5: ``transfer["trials"]`` deterministic trials of ``model`` on ``transfer["env"]`` (the
    first :data:`PAPER_TRIALS` are the paper's) and :data:`OWN_TRIALS` on its training env, counted by outcome;
    ``env_kwargs`` go to both envs (``observe_odometry: False``: sensors only) unless ``transfer["env_kwargs"]``
    gives the transfer env its own."""
    seed = transfer.get("seed", TRANSFER_SEED)
    own = tally(env_outcomes(model, env, OWN_TRIALS, seed + 10**4, env_kwargs))
    outcomes = env_outcomes(model, transfer["env"], transfer["trials"], seed, transfer.get("env_kwargs", env_kwargs))
    target = tally(outcomes)
    return {
        "transfer_env": transfer["env"],
        "transfer_trials": transfer["trials"],
        "transfer_paper_successes": tally(outcomes[:PAPER_TRIALS])["success"],
        **{f"transfer_{key}": value for key, value in target.items()},
        "own_env_success": own["success"] / OWN_TRIALS,
    }
