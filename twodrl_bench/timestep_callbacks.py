"""The callbacks of a timesteps job (:mod:`twodrl_bench.timesteps`): its goal checks, which keep the best check's
policy and stop once learned, and its checkpoints, with the ``Monitor`` files cut back on resume."""

from __future__ import annotations

import copy
import time
from pathlib import Path
from typing import Any

from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.monitor import Monitor, ResultsWriter

from sb3_twodrl.callbacks import PATIENCE, SUCCESS_THRESHOLD, GoalCheck, GoalRecord
from twodrl_bench import jobs
from twodrl_bench.experiment import Job
from twodrl_bench.timestep_measures import evaluate


class GoalChecks(BaseCallback):
    """Every ``protocol.check_every`` timesteps, at a rollout's start, ``protocol.check_episodes`` deterministic
    episodes on a fresh evaluation env seeded ``EVAL_SEED + seed``
    (:func:`~twodrl_bench.timestep_measures.evaluate`); ``[timestep, share that reached the goal]`` appended to
    ``state["checks"]`` (checkpointed with the job, so a resumed run checks as an uninterrupted one). The checks'
    time is part of the row's ``wall_s``.

    With ``protocol.keep_learned``, the policy of the best check is kept in ``state["kept"]`` (its timestep, goal
    rate, mean return and parameters, checkpointed too) and loaded back when training ends; training stops once
    the checks say the task is learned (:class:`sb3_twodrl.callbacks.GoalRecord`)."""

    def __init__(self, job: Job, state: dict[str, Any], make_env: Any):
        super().__init__()
        self.job, self.state, self.make_env = job, state, make_env
        self.record = GoalRecord(SUCCESS_THRESHOLD, PATIENCE)
        for timestep, share, mean_return in state.get("kept_checks", []):
            self.record.add(GoalCheck(timestep, share, mean_return))
        self._stop = False

    def _on_rollout_start(self) -> None:
        every = self.job.protocol.check_every
        checks = self.state.setdefault("checks", [])
        due = (checks[-1][0] // every + 1) * every if checks else every
        if not every or self.num_timesteps < due:
            return
        env = self.make_env()
        try:
            result = evaluate(self.model, env, self.job.protocol.check_episodes, None)
        finally:
            env.close()
        checks.append([self.num_timesteps, result["final_success_share"]])
        if not self.job.protocol.keep_learned:
            return
        check = GoalCheck(self.num_timesteps, result["final_success_share"], result["final_return"])
        self.state.setdefault("kept_checks", []).append([check.timesteps, check.goal_rate, check.mean_return])
        if self.record.add(check):
            self.state["kept"] = {**vars(check), "parameters": copy.deepcopy(self.model.policy.state_dict())}
        if self.record.learned:
            self.state["learned_at"] = self.num_timesteps
            self._stop = True

    def _on_step(self) -> bool:
        return not self._stop

    def _on_training_end(self) -> None:
        kept = self.state.get("kept")
        if kept is not None:
            self.model.policy.load_state_dict(kept["parameters"])


def _monitors(model: BaseAlgorithm) -> list[Monitor]:
    """The ``Monitor`` of each training env of ``model``, in env order."""
    monitors = []
    for env in model.get_env().unwrapped.envs:
        while not isinstance(env, Monitor):
            env = env.env
        monitors.append(env)
    return monitors


class Checkpoints(BaseCallback):
    """Checkpoints the job every ``protocol.checkpoint_every`` timesteps, at a rollout's start (a clean boundary:
    the update of the last rollout done), with the sizes of the ``Monitor`` files then; the files' open writers
    are left out of the checkpoint (:func:`restore_monitors` reopens them)."""

    def __init__(self, job: Job, state: dict[str, Any], budget: int):
        super().__init__()
        self.job, self.state, self.budget = job, state, budget
        self._clock = time.perf_counter()

    def _on_rollout_start(self) -> None:
        every, done = self.job.protocol.checkpoint_every, self.num_timesteps
        if not every or done - self.state["checkpoint_at"] < every or done >= self.budget:
            return
        self.state["checkpoint_at"] = done
        monitors = _monitors(self.model)
        writers = [m.results_writer for m in monitors]
        files = [w.file_handler.name for w in writers]
        elapsed = self.state["elapsed"] + time.perf_counter() - self._clock
        try:
            for monitor in monitors:
                monitor.results_writer = None  # an open file: not pickled
            extra = {**self.state, "elapsed": elapsed, "monitors": [(f, Path(f).stat().st_size) for f in files]}
            jobs.save(self.job, self.model, extra)
        finally:
            for monitor, writer in zip(monitors, writers, strict=True):
                monitor.results_writer = writer
        with jobs.progress_path(self.job.out_dir, self.job.name).open("a") as f:
            f.write(f"{done}\n")

    def _on_step(self) -> bool:
        return True


def restore_monitors(model: BaseAlgorithm, files: list[tuple[str, int]]) -> None:
    """Cut each training env's ``Monitor`` file back to its size at the checkpoint and append to it again."""
    for monitor, (name, size) in zip(_monitors(model), files, strict=True):
        with open(name, "r+b") as f:
            f.truncate(size)
        keys = (*monitor.reset_keywords, *monitor.info_keywords)
        monitor.results_writer = ResultsWriter(name, extra_keys=keys, override_existing=False)
