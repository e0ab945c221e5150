"""The epoch job: one (arm, seed) run of the paper's protocol (section 3.4.1), resumable from its last checkpoint.

Learning goes on in one ``learn()`` call; :class:`EpochCallback` counts finished learning trials
over all envs and, in the step in which the (e*K)-th ends, runs epoch e's M test trials (the
policy is the same whichever of that step's trials is the (e*K)-th: parameters change only
between rollouts). Trials of that step beyond e*K count toward epoch e + 1, so every epoch is
exactly K trials and no collected experience is thrown away at an epoch boundary. A stock arm (``a2c``, ``ppo``)
trains SB3's algorithm on the fast path (:func:`twodrl_bench.algorithms.fast_path`), its rows labelled by the arm.

Every ``checkpoint_every`` epochs, at the next rollout start (a clean boundary: the update of the
last rollout done, the buffer empty), the run is checkpointed (:mod:`.checkpoint`) together with
its rows so far; a run that finds a checkpoint of its protocol continues from it and produces the
rows an uninterrupted run produces (``wall_s`` aside, which adds the time before the interruption).
At the end the model is saved (``models/<arm>_seed<seed>.zip``, loadable by ``<Algo>.load``). With a
``transfer`` protocol key (paper section 3.5) the saved policy then runs deterministic trials on another
env (:func:`twodrl_bench.trials.transfer_columns`), reported in the last epoch's row.

:func:`run` is the epoch protocol's job (:func:`twodrl_bench.runner.run_job`): a job in, rows out; checkpoints and
resume are every job's (:func:`twodrl_bench.jobs.resume`).
"""

from __future__ import annotations

import copy
import importlib
import math
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import VecEnv

from sb3_twodrl.callbacks import NavigationMetricsCallback
from twodrl_bench import jobs
from twodrl_bench.algorithms import algo_class, fast_path, make_model
from twodrl_bench.checkpoint import set_rng_state
from twodrl_bench.experiment import Job, with_seed
from twodrl_bench.protocol import LEARNING, METRICS, ROUTES, trial_seed
from twodrl_bench.trials import run_test_trials, transfer_columns
from twodrl_zoo.hyperparams import python_expression
from twodrl_zoo.vec_env import make_test_env, make_train_env

Row = dict[str, Any]


class EpochCallback(BaseCallback):
    """Epochs of K learning trials, each followed by the M test trials; checkpoints; stops after the last."""

    def __init__(self, job: Job, test_env: VecEnv, nav: NavigationMetricsCallback, state: dict[str, Any]):
        super().__init__()
        self.job, self.protocol, self.test_env, self.nav, self.state = job, job.protocol, test_env, nav, state
        self._clock = time.perf_counter()
        self._rng: dict[str, Any] | None = state.pop("rng", None)

    def _on_training_start(self) -> None:
        nav = self.state.get("nav")
        if nav is not None:  # resumed: the rollout metrics' window as it was
            self.nav.episodes, self.nav.total_episodes, self.nav._tracker = nav
        if self._rng is not None:
            set_rng_state(self._rng)

    def elapsed(self) -> float:
        return self.state["elapsed"] + time.perf_counter() - self._clock

    def _on_rollout_start(self) -> None:
        s, every = self.state, self.protocol.checkpoint_every
        if every and s["epoch"] - s["checkpoint_epoch"] >= every and s["epoch"] < self.protocol.epochs:
            s["checkpoint_epoch"] = s["epoch"]
            nav = (self.nav.episodes, self.nav.total_episodes, self.nav._tracker)
            jobs.save(self.job, self.model, {**s, "elapsed": self.elapsed(), "nav": nav})

    def _on_rollout_end(self) -> None:
        """Tally the rollout's temperatures (2D-RL algorithms: ``inverse_temperatures`` in the buffer)."""
        inverse = getattr(self.model.rollout_buffer, "inverse_temperatures", None)
        if inverse is None:
            return
        tally = self.state.setdefault("learning", [0, 0, 0.0, 0])  # interest-set, actions, sum of T, tempered
        tempered = inverse[inverse > 0]
        tally[0] += round(self.model.interest_share(inverse) * inverse.size)
        tally[1] += inverse.size
        tally[2] += float(np.sum(1.0 / tempered, dtype=np.float64))
        tally[3] += tempered.size

    def _learning_metrics(self) -> dict[str, float]:
        """:data:`~.protocol.LEARNING` of the rollouts that ended since the last epoch; the tally restarts."""
        inside, steps, temperature, tempered = self.state.pop("learning", [0, 0, 0.0, 0])
        share = inside / steps if steps else math.nan
        return dict(zip(LEARNING, (share, temperature / tempered if tempered else math.nan), strict=True))

    def _on_step(self) -> bool:
        s, job, protocol = self.state, self.job, self.protocol
        s["episodes"] += int(np.sum(self.locals["dones"]))
        while s["episodes"] >= (s["epoch"] + 1) * protocol.learn_episodes and s["epoch"] < protocol.epochs:
            s["epoch"] += 1
            metrics = run_test_trials(self.model, self.test_env, trial_seed(job.seed, s["epoch"]))
            row = {
                "env": job.experiment.env,
                "algo": job.arm.algo,
                "seed": job.seed,
                "epoch": s["epoch"],
                "learn_episodes": s["epoch"] * protocol.learn_episodes,
                **{key: metrics.get(key, math.nan) for key in METRICS},
                **self._learning_metrics(),
                **coefficient_columns(self.model),
                "env_steps": int(self.num_timesteps),
                "wall_s": round(self.elapsed(), 3),
            }
            s["rows"].append(row)
            for key in METRICS:
                self.logger.record(f"test/{key}", row[key])
            self.logger.record("test/epoch", s["epoch"])
            self.logger.dump(self.num_timesteps)
            with jobs.progress_path(job.out_dir, job.name).open("a") as f:
                f.write(f"{s['epoch']}\n")
        return s["epoch"] < protocol.epochs


def coefficient_columns(model: BaseAlgorithm) -> dict[str, float]:
    """For a learned entropy coefficient (:mod:`twodrl_bench.algorithms.auto_entropy`): ``ent_coef`` and
    ``entropy_fraction`` of the last update; none for a fixed coefficient."""
    if not getattr(model, "ent_coef_auto", False):
        return {}
    latest = model.ent_coef_latest or [math.nan] * 3
    return {"ent_coef": latest[1], "entropy_fraction": latest[2]}


def _new_model(job: Job) -> BaseAlgorithm:
    set_random_seed(job.seed)
    hp = copy.deepcopy(job.arm.hyperparams)  # SB3 fills in policy_kwargs in place (A2C's RMSprop)
    if isinstance(hp.get("policy_kwargs"), str):
        hp["policy_kwargs"] = python_expression(hp["policy_kwargs"])
    n_envs = int(hp.pop("n_envs", 1))
    experiment, protocol = job.experiment, job.protocol
    env = make_train_env(experiment.env, n_envs, job.seed, protocol.vec_env, job.env_kwargs)
    tb = str(Path(job.out_dir) / "tb") if protocol.tensorboard else None
    return make_model(fast_path(job.arm.algo), env, hp, seed=job.seed, device="cpu", tensorboard_log=tb)


def train(job: Job) -> list[Row]:
    """Train ``job``'s arm for its protocol's epochs (resuming its checkpoint, :func:`twodrl_bench.jobs.resume`);
    the CSV rows. The last checkpoint stays: a longer run of the same job extends it."""
    experiment, protocol = job.experiment, job.protocol
    for package in experiment.gym_packages:
        importlib.import_module(package)
    th.set_num_threads(1)
    progress = jobs.progress_path(job.out_dir, job.name)
    progress.parent.mkdir(parents=True, exist_ok=True)
    resumed = jobs.resume(job)
    if resumed is not None:
        model, rng, state = resumed
        state["rng"] = rng
    else:
        model = _new_model(job)
        state = {"episodes": 0, "epoch": 0, "checkpoint_epoch": 0, "rows": [], "elapsed": 0.0}
        if protocol.tensorboard:  # an interrupted attempt that left no checkpoint
            for stale in (Path(job.out_dir) / "tb").glob(f"{job.name}_*"):
                shutil.rmtree(stale, ignore_errors=True)
    progress.write_text("".join(f"{row['epoch']}\n" for row in state["rows"]))
    test_env = make_test_env(experiment.env, protocol.test_episodes, protocol.vec_env, job.env_kwargs)
    nav = NavigationMetricsCallback(routes=ROUTES)
    epochs = EpochCallback(job, test_env, nav, state)
    if state["epoch"] < protocol.epochs:
        model.learn(10**15, callback=[nav, epochs], tb_log_name=job.name, log_interval=100, reset_num_timesteps=False)
    if protocol.save_model:
        path = jobs.model_path(job.out_dir, job.name)
        path.parent.mkdir(parents=True, exist_ok=True)
        model.save(path)
    model.get_env().close()
    test_env.close()
    return state["rows"]


def run(job: Job) -> list[Row]:
    """The rows of ``job`` (an arm and seed of an epoch protocol): :func:`train`, then its transfer trials if its
    protocol has a ``transfer``; each row starts with the arm's name."""
    rows = [{"arm": job.arm_name, **row} for row in train(job)]
    transfer = job.protocol.transfer
    if transfer:
        model = algo_class(fast_path(job.arm.algo)).load(jobs.model_path(job.out_dir, job.name), device="cpu")
        rows[-1].update(transfer_columns(model, job.experiment.env, job.env_kwargs, with_seed(transfer, job.seed)))
    jobs.finish(job)
    return rows
