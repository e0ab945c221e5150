"""The epoch job: one (arm, seed) run of the paper's protocol (section 3.4.1), resumable from its last checkpoint.

Learning goes on in one ``learn()`` call; :class:`EpochCallback` counts finished learning trials
over all envs and, in the step in which the (e*K)-th ends, runs epoch e's M test trials (the
policy is the same whichever of that step's trials is the (e*K)-th: parameters change only
between rollouts). Trials of that step beyond e*K count toward epoch e + 1, so every epoch is
exactly K trials and no collected experience is thrown away at an epoch boundary.

Every ``checkpoint_every`` epochs, at the next rollout start (a clean boundary: the update of the
last rollout done, the buffer empty), the run is checkpointed (:mod:`.checkpoint`) together with
its rows so far; a run that finds a checkpoint of its protocol continues from it and produces the
rows an uninterrupted run produces (``wall_s`` aside, which adds the time before the interruption).
At the end the model is saved (``models/<arm>_seed<seed>.zip``, loadable by ``<Algo>.load``). With a
``transfer`` protocol key (paper section 3.5) the saved policy then runs deterministic trials on another
env (:func:`transfer_columns`), reported in the last epoch's row.

:func:`run_job` is the study runner's entry (:mod:`twodrl_bench.runner`): plain data in, rows out.
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
from sb3_twodrl.hyperparams import evaluate
from twodrl_bench.algos import algo_class
from twodrl_bench.checkpoint import load_checkpoint, save_checkpoint, set_rng_state
from twodrl_bench.protocol import LEARNING, METRICS, ROUTES, RunSpec, trial_seed
from twodrl_bench.trials import run_test_trials, tally, trial_outcomes
from twodrl_bench.vec_env import make_test_env, make_train_env

Row = dict[str, Any]
PAPER_TRIALS = 10
"""Trials on the real robot per policy in the paper (section 3.5): the first of a transfer's trials."""
TRANSFER_SEED = 1_000_003
"""The held-out seed of a transfer's trials (sub-env ``i`` seeded ``seed + i``); its own env's: ``seed + 10**4``."""
OWN_TRIALS = 10
"""Trials of a transferred policy in its own training env (did it learn at all?)."""


def checkpoint_path(out_dir: str | Path, name: str) -> Path:
    return Path(out_dir) / "checkpoints" / f"{name}.pkl"


def model_path(out_dir: str | Path, name: str) -> Path:
    return Path(out_dir) / "models" / f"{name}.zip"


def progress_path(out_dir: str | Path, name: str) -> Path:
    """One line per finished epoch of a running job: what ``sb3-twodrl-bench status`` reads."""
    return Path(out_dir) / "progress" / f"{name}.txt"


class EpochCallback(BaseCallback):
    """Epochs of K learning trials, each followed by the M test trials; checkpoints; stops after the last."""

    def __init__(self, spec: RunSpec, test_env: VecEnv, nav: NavigationMetricsCallback, state: dict[str, Any]):
        super().__init__()
        self.spec, self.test_env, self.nav, self.state = spec, test_env, nav, state
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
        s, every = self.state, self.spec.checkpoint_every
        if every and s["epoch"] - s["checkpoint_epoch"] >= every and s["epoch"] < self.spec.epochs:
            s["checkpoint_epoch"] = s["epoch"]
            nav = (self.nav.episodes, self.nav.total_episodes, self.nav._tracker)
            extra = {**s, "elapsed": self.elapsed(), "nav": nav}
            save_checkpoint(checkpoint_path(self.spec.out_dir, self.spec.name), self.model, extra)

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
        s, spec = self.state, self.spec
        s["episodes"] += int(np.sum(self.locals["dones"]))
        while s["episodes"] >= (s["epoch"] + 1) * spec.learn_episodes and s["epoch"] < spec.epochs:
            s["epoch"] += 1
            metrics = run_test_trials(self.model, self.test_env, trial_seed(spec.seed, s["epoch"]))
            row = {
                "env": spec.env_id,
                "algo": spec.algo,
                "seed": spec.seed,
                "epoch": s["epoch"],
                "learn_episodes": s["epoch"] * spec.learn_episodes,
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
            with progress_path(spec.out_dir, spec.name).open("a") as f:
                f.write(f"{s['epoch']}\n")
        return s["epoch"] < spec.epochs


def coefficient_columns(model: BaseAlgorithm) -> dict[str, float]:
    """For a learned entropy coefficient (:mod:`twodrl_bench.auto_entropy`): ``ent_coef`` and
    ``entropy_fraction`` of the last update; none for a fixed coefficient."""
    if not getattr(model, "ent_coef_auto", False):
        return {}
    latest = model.ent_coef_latest or [math.nan] * 3
    return {"ent_coef": latest[1], "entropy_fraction": latest[2]}


def _new_model(spec: RunSpec) -> BaseAlgorithm:
    set_random_seed(spec.seed)
    hp = copy.deepcopy(spec.hyperparams)  # SB3 fills in policy_kwargs in place (A2C's RMSprop)
    n_envs = int(hp.pop("n_envs", 1))
    policy = hp.pop("policy", "MlpPolicy")
    env = make_train_env(spec.env_id, n_envs, spec.seed, spec.vec_env, spec.env_kwargs)
    tb = str(Path(spec.out_dir) / "tb") if spec.tensorboard else None
    return algo_class(spec.algo)(policy, env, seed=spec.seed, device="cpu", tensorboard_log=tb, **hp)


def run_pair(spec: RunSpec) -> list[Row]:
    """Train ``spec.algo`` with ``spec.seed`` for ``spec.epochs`` epochs (resuming a checkpoint); the CSV rows."""
    for package in spec.gym_packages:
        importlib.import_module(package)
    th.set_num_threads(1)
    ckpt = checkpoint_path(spec.out_dir, spec.name)
    progress = progress_path(spec.out_dir, spec.name)
    progress.parent.mkdir(parents=True, exist_ok=True)
    if ckpt.exists():
        model, rng, state = load_checkpoint(ckpt)
        if state["protocol"] != spec.protocol():
            raise ValueError(f"{ckpt} was written by another protocol: {state['protocol']} != {spec.protocol()}")
        state["rng"] = rng
    else:
        model = _new_model(spec)
        state = {"protocol": spec.protocol(), "episodes": 0, "epoch": 0, "checkpoint_epoch": 0, "rows": []}
        state["elapsed"] = 0.0
        if spec.tensorboard:  # an interrupted attempt that left no checkpoint
            for stale in (Path(spec.out_dir) / "tb").glob(f"{spec.name}_*"):
                shutil.rmtree(stale, ignore_errors=True)
    progress.write_text("".join(f"{row['epoch']}\n" for row in state["rows"]))
    test_env = make_test_env(spec.env_id, spec.test_episodes, spec.vec_env, spec.env_kwargs)
    nav = NavigationMetricsCallback(routes=ROUTES)
    epochs = EpochCallback(spec, test_env, nav, state)
    if state["epoch"] < spec.epochs:
        model.learn(10**15, callback=[nav, epochs], tb_log_name=spec.name, log_interval=100, reset_num_timesteps=False)
    if spec.save_model:
        path = model_path(spec.out_dir, spec.name)
        path.parent.mkdir(parents=True, exist_ok=True)
        model.save(path)
    model.get_env().close()
    test_env.close()
    return state["rows"]


def run_job(
    arm: dict[str, Any],
    env: str,
    env_kwargs: dict[str, Any],
    protocol: dict[str, Any],
    seed: int,
    out_dir: str,
    gym_packages: list[str],
) -> list[Row]:
    """The rows of one (arm, seed) of an epoch protocol: :func:`run_pair` of the arm's resolved settings.

    ``arm``: ``{"name", "algo", "hyperparams"}`` (:func:`twodrl_bench.spec.resolve`; a ``policy_kwargs``
    string is evaluated by :func:`sb3_twodrl.hyperparams.evaluate`); ``protocol``: ``{epochs, learn_episodes,
    test_episodes, vec_env, checkpoint_every, save_model, tensorboard}``. Each row starts with the arm's name.
    """
    hyperparams = dict(arm["hyperparams"])
    if isinstance(hyperparams.get("policy_kwargs"), str):
        hyperparams["policy_kwargs"] = evaluate(hyperparams["policy_kwargs"])
    spec = RunSpec(
        env_id=env,
        algo=arm["algo"],
        seed=seed,
        epochs=protocol["epochs"],
        learn_episodes=protocol["learn_episodes"],
        test_episodes=protocol["test_episodes"],
        hyperparams=hyperparams,
        out_dir=out_dir,
        gym_packages=list(gym_packages),
        vec_env=protocol["vec_env"],
        checkpoint_every=protocol["checkpoint_every"],
        save_model=protocol["save_model"],
        tensorboard=protocol["tensorboard"],
        env_kwargs=dict(env_kwargs),
        label=arm["name"],
    )
    rows = [{"arm": arm["name"], **row} for row in run_pair(spec)]
    if protocol.get("transfer"):
        model = algo_class(spec.algo).load(model_path(out_dir, spec.name), device="cpu")
        rows[-1].update(transfer_columns(model, env, dict(env_kwargs), protocol["transfer"]))
    checkpoint_path(out_dir, spec.name).unlink(missing_ok=True)
    progress_path(out_dir, spec.name).unlink(missing_ok=True)
    return rows


def _outcomes(model: BaseAlgorithm, env_id: str, n: int, seed: int, env_kwargs: dict[str, Any]) -> list[str]:
    """Outcomes of ``n`` deterministic trials on ``env_id`` (sub-env ``i`` seeded ``seed + i``)."""
    env = make_test_env(env_id, n, env_kwargs=env_kwargs)
    try:
        return trial_outcomes(model, env, seed)
    finally:
        env.close()


def transfer_columns(model: BaseAlgorithm, env: str, env_kwargs: dict[str, Any], transfer: dict[str, Any]) -> Row:
    """Paper section 3.5: ``transfer["trials"]`` deterministic trials of ``model`` on ``transfer["env"]`` (the
    first :data:`PAPER_TRIALS` are the paper's) and :data:`OWN_TRIALS` on its training env, counted by outcome;
    ``env_kwargs`` go to both envs (``observe_odometry: False``: sensors only)."""
    seed = transfer.get("seed", TRANSFER_SEED)
    own = tally(_outcomes(model, env, OWN_TRIALS, seed + 10**4, env_kwargs))
    outcomes = _outcomes(model, transfer["env"], transfer["trials"], seed, env_kwargs)
    target = tally(outcomes)
    return {
        "transfer_env": transfer["env"],
        "transfer_trials": transfer["trials"],
        "transfer_paper_successes": tally(outcomes[:PAPER_TRIALS])["success"],
        **{f"transfer_{key}": value for key, value in target.items()},
        "own_env_success": own["success"] / OWN_TRIALS,
    }
