"""The timesteps job: one (arm, seed) trained by the train command's ``ExperimentManager``, then a final deterministic
evaluation.

:func:`run` is the job of an experiment whose protocol is :class:`~twodrl_bench.protocol.TimestepsProtocol`. The
arm's model and envs are made as ``sb3-twodrl-train`` makes them, from its resolved entry; the training envs'
``Monitor`` records every training episode's return and punishment events, from which come the learning curve and
the training event rates; the final model then runs ``eval_episodes`` deterministic episodes on a fresh env seeded
``EVAL_SEED + seed``, apart from training (with the run's ``VecNormalize`` statistics, frozen, where the entry
normalises). Training is checkpointed every ``checkpoint_every`` timesteps and resumed as every job is
(:mod:`twodrl_bench.jobs`); the ``Monitor`` files are cut back to the checkpoint on resume.

Keys this job reads, beside the fields every spec has:

- ``protocol.timesteps``: the training budget (rl-zoo3's ``--n-timesteps``); ``null``: the entry's ``n_timesteps``.
- ``protocol.eval_episodes``: the final evaluation's deterministic episodes.
- ``protocol.events`` (optional): the ``info`` key holding the episode's punishment events so far; the training
  envs' ``Monitor`` records it (``monitor_kwargs``) and the evaluation reads it at each episode's end.
- ``protocol.entry`` (optional): the name of the settings entry both arms read (default: the spec's ``env``),
  e.g. rl-zoo3's ``CartPole-v1`` entry for ``CliffWalkingSplit-v1``, which has none of its own.
- ``protocol.task`` (optional): the rows' ``task`` label (default: the spec's ``env``).
- ``protocol.check_every`` (optional, 0: none): timesteps between goal checks, each ``protocol.check_episodes``
  deterministic episodes on a fresh evaluation env (:class:`~twodrl_bench.timestep_callbacks.GoalChecks`); the
  row's ``checks`` and ``first_goal_at`` (the first check's timestep at which an episode reached the goal,
  ``info["is_success"]``).
- ``protocol.keep_learned`` (optional, false): as ``sb3-twodrl-train`` does (:mod:`twodrl_zoo.manager`), keep the
  policy of the best check (:class:`sb3_twodrl.callbacks.GoalRecord`) and stop training once
  :data:`~sb3_twodrl.callbacks.PATIENCE` checks in a row reach :data:`~sb3_twodrl.callbacks.SUCCESS_THRESHOLD`; the
  final evaluation and the transfer then run the kept policy. Columns ``kept_at``, ``learned_at`` (NaN if never)
  and ``steps`` (the timesteps trained: one vector step past ``learned_at`` when stopped, as the stop comes at the
  first step after the rollout's check).
- ``protocol.transfer`` (optional): ``{env, trials, seed, env_kwargs}``, the final policy's deterministic trials on
  another env (:func:`twodrl_bench.trials.transfer_columns`, paper section 3.5), columns ``transfer_*``.
- ``protocol.stand_ins`` (optional): ``{trials, seed, env_kwargs}``, the final policy's deterministic trials from
  the map's start on both stand-in robots, the physics one and the artifact model
  (:func:`twodrl_bench.stand_ins.stand_in_trials`, needs ``sb3-twodrl[mujoco]``), columns ``<robot>_<outcome>``
  (``mujoco_success``, ``real_collision``, ...).
- ``env_kwargs``: the job's (``{seed}`` in a value is its seed). Where the env derives settings from them
  (:func:`twodrl_zoo.hyperparams.derived_settings` at the studies' revision
  :data:`~twodrl_bench.settings.STUDY_REVISION`: a map other than the paper's), they apply as ``sb3-twodrl-train``
  applies them: its hyperparameters under the arm's ``override``, its training options under ``env_kwargs``, its
  test options (the map's start, the time limit) in the evaluation, the checks and the transfer.
- ``arms.<name>.settings``: ``packaged`` (default), ``rl-zoo3`` or a folder
  (:func:`twodrl_bench.settings.settings_file`); ``arms.<name>.override``: settings over the entry.

Resolving a spec's timesteps arm is :func:`resolve_arm`; :func:`run_plain_job` runs a job given as plain data.

Requires the ``zoo`` extra.
"""

from __future__ import annotations

import argparse
import copy
import importlib
import json
import math
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm

from twodrl_bench import jobs
from twodrl_bench.experiment import Arm, Experiment, Job, with_seed
from twodrl_bench.protocol import TimestepsProtocol
from twodrl_bench.settings import STUDY_REVISION, check_entry, timesteps_entry
from twodrl_bench.stand_ins import stand_in_columns, stand_in_trials
from twodrl_bench.timestep_callbacks import Checkpoints, GoalChecks, restore_monitors
from twodrl_bench.timestep_measures import (
    EVAL_SEED,
    eval_env,
    evaluate,
    first_goal,
    learning_curve,
    training_episodes,
)
from twodrl_bench.trials import transfer_columns
from twodrl_zoo.hyperparams import derived_settings, resolve
from twodrl_zoo.manager import ExperimentManager

Row = dict[str, Any]


def check_protocol(protocol: dict[str, Any]) -> TimestepsProtocol:
    """The timesteps protocol of a spec's ``protocol`` mapping.

    :raises ValueError: naming the key, for an unknown key or a bad budget, episode count or label
    """
    return TimestepsProtocol.from_mapping(protocol)


def resolve_arm(arm: dict[str, Any], env: str, protocol: dict[str, Any]) -> dict[str, Any]:
    """The rl-zoo3 entry ``arm`` (a spec's ``{algo, override, settings}``) trains with on ``env`` under ``protocol``
    (:func:`twodrl_bench.settings.timesteps_entry`, what the study object resolves a timesteps arm to)."""
    return timesteps_entry(arm, env, protocol)


def _new_model(job: Job, entry: dict[str, Any], log: Path) -> tuple[BaseAlgorithm, Path]:
    """``job``'s model and env as ``sb3-twodrl-train`` makes them (seed, :class:`twodrl_zoo.manager.ExperimentManager`)
    from the resolved ``entry``, without goal checks and with rl-zoo3's envs (a ``Monitor`` per env, whose files
    :func:`~twodrl_bench.timestep_measures.training_episodes` reads); its run folder."""
    from stable_baselines3.common.utils import set_random_seed

    algo, env, seed = job.arm.algo, job.experiment.env, job.seed
    shutil.rmtree(log, ignore_errors=True)  # what an interrupted attempt without a checkpoint left
    log.mkdir(parents=True)
    timesteps = job.protocol.timesteps or -1
    options = {"algo": algo, "env": env, "seed": seed, "n_timesteps": timesteps}
    set_random_seed(seed)
    manager = ExperimentManager(
        argparse.Namespace(**options, log_folder=str(log), vec_env="dummy", device="cpu", eval_freq=-1),
        algo,
        env,
        str(log),
        n_timesteps=timesteps,
        eval_freq=-1,
        seed=seed,
        log_interval=-1,
        vec_env_type="dummy",
        device="cpu",
        entry=entry,
        batched=False,
    )
    model, _ = manager.setup_experiment()
    return model, Path(manager.save_path)


def run(job: Job) -> list[Row]:
    """Train ``job``'s arm with the train command's ``ExperimentManager`` (its logs in
    ``<out_dir>/zoo/<arm>_seed<seed>``), checkpointed (:class:`~twodrl_bench.timestep_callbacks.Checkpoints`) and
    resumed (:func:`twodrl_bench.jobs.resume`) as every job is, then evaluate the final model; its one row.

    The row: ``task``, ``env``, ``arm``, ``seed``, ``n_timesteps``; the final evaluation's ``final_return`` (mean),
    ``final_return_std``, ``final_length``, ``final_events`` (per episode), ``final_event_share``; over the
    training episodes ``train_episodes``, ``train_return``, ``train_events_per_episode``, ``train_event_share``;
    ``curve`` (:func:`learning_curve` as JSON text, so that the row is flat); for an arm whose entropy coefficient
    is learned (:mod:`twodrl_bench.algorithms.auto_entropy`), ``ent_coef_course`` (the final model's, as JSON
    text); ``wall_s``.
    """
    import torch as th

    from twodrl_bench.algorithms import ALGOS, algo_class
    from twodrl_bench.checkpoint import set_rng_state
    from twodrl_zoo.zoo import register_zoo

    clock = time.perf_counter()
    experiment, protocol, arm = job.experiment, job.protocol, job.arm
    algo = algo_class(arm.algo)
    register_zoo(ALGOS)  # the manager builds the arm's model from rl-zoo3's table: the bench's names in it
    for package in experiment.gym_packages:
        importlib.import_module(package)
    th.set_num_threads(1)
    env, events, env_kwargs = experiment.env, protocol.events, job.env_kwargs
    derived = derived_settings(env, env_kwargs, revision=STUDY_REVISION)
    settings = resolve(copy.deepcopy(arm.hyperparams), derived, copy.deepcopy(arm.override), env_kwargs)
    entry = settings.entry
    check_entry(arm.name, entry, protocol.as_dict())
    test_kwargs = settings.eval_env_kwargs
    if protocol.check_every and entry.get("normalize"):
        raise ValueError(f"arm {arm.name!r}: protocol.check_every needs an entry without normalize")
    budget = int(protocol.timesteps or entry["n_timesteps"])

    def make_check_env() -> Any:
        return eval_env(env, entry, test_kwargs, EVAL_SEED + job.seed)

    jobs.progress_path(job.out_dir, job.name).parent.mkdir(parents=True, exist_ok=True)
    resumed = jobs.resume(job)
    if resumed is None:
        model, run_dir = _new_model(job, entry, Path(job.out_dir) / "zoo" / job.name)
        state = {"run": str(run_dir), "checkpoint_at": 0, "elapsed": 0.0, "checks": []}
        jobs.progress_path(job.out_dir, job.name).write_text("")
        model.learn(budget, callback=[GoalChecks(job, state, make_check_env), Checkpoints(job, state, budget)])
    else:
        model, rng, state = resumed
        run_dir = Path(state["run"])
        restore_monitors(model, state.pop("monitors"))
        set_rng_state(rng)
        remaining = budget - model.num_timesteps
        callbacks = [GoalChecks(job, state, make_check_env), Checkpoints(job, state, budget)]
        model.learn(remaining, callback=callbacks, reset_num_timesteps=False)
    model.env.close()
    model.save(run_dir / env)
    statistics = model.get_vec_normalize_env()
    if statistics is not None:
        statistics.save(str(run_dir / env / "vecnormalize.pkl"))
    train_eps = training_episodes(run_dir, int(entry.get("n_envs", 1)), events)
    model = algo.load(run_dir / f"{env}.zip", device="cpu")
    final_env = eval_env(env, entry, test_kwargs, EVAL_SEED + job.seed, run_dir / env / "vecnormalize.pkl")
    final = evaluate(model, final_env, protocol.eval_episodes, events)
    final_env.close()
    checks = (
        {"checks": json.dumps(state["checks"]), "first_goal_at": first_goal(state["checks"])}
        if protocol.check_every
        else {}
    )
    if protocol.keep_learned:
        kept = state.get("kept")
        checks["kept_at"] = kept["timesteps"] if kept else math.nan
        checks["learned_at"] = state.get("learned_at", math.nan)
        checks["steps"] = model.num_timesteps
    transfer = (
        transfer_columns(model, env, env_kwargs, with_seed(protocol.transfer, job.seed)) if protocol.transfer else {}
    )
    if protocol.stand_ins:
        stand_ins = with_seed(protocol.stand_ins, job.seed)
        counts = stand_in_trials(model, stand_ins["trials"], stand_ins["seed"], stand_ins.get("env_kwargs", env_kwargs))
        transfer = {**transfer, **stand_in_columns(counts)}
    found = len(train_eps) > 0
    learned_coefficient = getattr(model, "ent_coef_auto", False)
    course = {"ent_coef_course": json.dumps(model.ent_coef_course)} if learned_coefficient else {}
    jobs.finish(job)
    return [
        {
            "task": protocol.task or env,
            "env": env,
            "arm": arm.name,
            "seed": job.seed,
            "n_timesteps": budget,
            **final,
            "train_episodes": len(train_eps),
            "train_return": float(train_eps[:, 1].mean()) if found else math.nan,
            "train_events_per_episode": float(train_eps[:, 2].mean()) if found else math.nan,
            "train_event_share": float(np.mean(train_eps[:, 2] > 0)) if found else math.nan,
            "curve": json.dumps(learning_curve(train_eps, budget)),
            **course,
            **checks,
            **transfer,
            "wall_s": round(state["elapsed"] + time.perf_counter() - clock, 1),
        }
    ]


def run_plain_job(
    arm: dict[str, Any],
    env: str,
    env_kwargs: dict[str, Any],
    protocol: dict[str, Any],
    seed: int,
    out_dir: str,
    gym_packages: list[str],
) -> list[Row]:
    """:func:`run` of a job given as plain data: ``arm`` as ``{name, algo, hyperparams}`` (``hyperparams``
    :func:`resolve_arm`'s entry), the spec's ``env``, ``env_kwargs``, ``protocol`` and ``gym_packages``.

    :raises ValueError: naming the argument, for a bad arm, protocol or seed
    """
    timesteps = check_protocol(protocol)
    if not isinstance(arm.get("name"), str) or not arm["name"] or not isinstance(arm.get("hyperparams"), dict):
        raise ValueError(f"arm must be {{name, algo, hyperparams}} (resolve_arm's entry), got {arm!r}")
    resolved = Arm(arm["name"], arm.get("algo"), {}, "packaged", arm["hyperparams"], {})
    experiment = Experiment(
        name=arm["name"],
        env=env,
        env_kwargs=dict(env_kwargs),
        gym_packages=tuple(gym_packages),
        protocol=timesteps,
        seeds=(seed,),
        arms={arm["name"]: resolved},
        report="benchmark",
    )
    return run(Job(experiment, arm["name"], seed, out_dir))
