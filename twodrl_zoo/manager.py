"""rl-zoo3's ``ExperimentManager`` with this project's settings, goal checks and batched envs: the model factory of
``sb3-twodrl-train`` and of the bench's timesteps protocol (:mod:`twodrl_bench.timesteps`).

What it changes of rl-zoo3's (everything else, every option, the run folder, is rl-zoo3's):

- **settings**: the env's task facts derive settings (:func:`twodrl_zoo.hyperparams.derived_settings`) that go
  between the hyperparameter file and what the user passes (:func:`twodrl_zoo.hyperparams.resolve`): the file
  < the task < ``--hyperparams`` (and ``-n``), and where goal checks stop training once learned the budget (the
  derived one, or the file's, e.g. the paper's office's 1M steps) becomes a ceiling :data:`CEILING` times as long
  (unless the user gives one); the training envs get the task's
  training options, the evaluation envs its test options (a map's start, its time limit) unless the user gives
  their own;
- **goal checks**: the evaluation is :class:`sb3_twodrl.callbacks.GoalCheckCallback`, which keeps the policy with
  the best goal rate and stops once :data:`PATIENCE` checks in a row reach :data:`SUCCESS_THRESHOLD` (each check
  ``--eval-episodes`` episodes, or the task's own number where readings vary; with ``n_eval_envs``
  :data:`SIDE_BY_SIDE`, the train command's default, they run side by side on a batched env, one policy call per
  step for all of them); the model
  saved as ``<env>.zip`` is the kept one, and ``goal_checks.json`` in the run folder says which check it was,
  whether any check passed, what every check gave and how long training took; :data:`SAVED` lists the run
  folders this process saved (the train command reports on its own run, not on a folder guessed from argv);
- **batched envs**: where the registry gives the env a same-step-autoreset vector entry point
  (:func:`twodrl_zoo.vec_env.has_batched_env`) and the entry wraps nothing, the training and evaluation envs are
  that batch (:class:`~twodrl_zoo.vec_env.VectorEnvAdapter`, under one ``VecMonitor``): the same episodes as
  ``DummyVecEnv`` of single envs, several times faster.

Two options of its own, which the bench sets: ``entry``, a run's entry resolved already
(:func:`twodrl_zoo.hyperparams.resolve`), read in place of the hyperparameter file's with nothing derived over it
(so no ceiling); ``batched=False``, rl-zoo3's envs (a ``Monitor`` per env, ``DummyVecEnv``) even where there is a
batch.

Requires the ``zoo`` extra.
"""

from __future__ import annotations

import copy
import inspect
import json
import os
import time
from collections import OrderedDict
from typing import Any

from rl_zoo3.callbacks import SaveVecNormalizeCallback
from rl_zoo3.exp_manager import ExperimentManager as ZooExperimentManager
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecMonitor

from sb3_twodrl.callbacks import PATIENCE, SUCCESS_THRESHOLD, GoalCheckCallback
from twodrl_zoo.hyperparams import derived_settings, resolve
from twodrl_zoo.vec_env import has_batched_env, make_train_env

__all__ = ["CEILING", "CHECKS_FILE", "PATIENCE", "SAVED", "SIDE_BY_SIDE", "SUCCESS_THRESHOLD", "ExperimentManager"]

CEILING = 2
"""The budget's factor when goal checks stop training once learned: the early stop ends most runs well before, so
the ceiling costs only the runs that have not learned (on the development offices, ``results/reliability``: 31 of
32 runs learned with it, 28 with the budget alone, at most 29 with a restart; an exploratory choice, its candidate
and rule added after 21 of the 32 runs had been watched)."""
CHECKS_FILE = "goal_checks.json"
"""The run folder's record of the goal checks, the kept policy and the training time."""
ZOO_EVAL_EPISODES = 5
"""rl-zoo3's ``--eval-episodes`` default: a task's own check episodes (:mod:`twodrl_zoo.recipe`) replace it only,
so a user's other value wins."""
SIDE_BY_SIDE = 0
"""``n_eval_envs`` meaning "a goal check's episodes side by side": as many eval envs as the check's episodes on a
batched env (a check is then one batched rollout: on the simulator's exact readings the same episodes as one env at
a time, with a fifth of the policy calls), else one. ``sb3-twodrl-train`` passes it unless the user gives
``--n-eval-envs``."""
SAVED: list[str] = []
"""The run folders (rl-zoo3's ``save_path``) this process saved a model to, the latest last."""


class ExperimentManager(ZooExperimentManager):
    """rl-zoo3's ``ExperimentManager`` (same arguments, and ``entry`` and ``batched``) with the changes of the module
    docstring."""

    def __init__(self, *args: Any, entry: dict[str, Any] | None = None, batched: bool = True, **kwargs: Any) -> None:
        bound = inspect.signature(ZooExperimentManager.__init__).bind(self, *args, **kwargs)
        bound.apply_defaults()
        given = bound.arguments
        given.pop("self")
        stops = given["eval_freq"] > 0 and not given["optimize_hyperparameters"]
        user_budget = given["n_timesteps"] > 0 or "n_timesteps" in (given.get("hyperparams") or {})
        self.ceiling = entry is None and stops and not user_budget  # the budget's a ceiling CEILING times as long
        self.readings_vary = False  # the task's readings vary from visit to visit (recipe revision 2 says so)
        derived = None if entry is not None else derived_settings(given["env_id"], given.get("env_kwargs"))
        if derived is not None:
            resolved = resolve(
                {}, derived, given.get("hyperparams"), given.get("env_kwargs"), given.get("eval_env_kwargs")
            )
            given["hyperparams"] = {k: v for k, v in resolved.entry.items() if k != "env_kwargs"}
            given["env_kwargs"], given["eval_env_kwargs"] = resolved.env_kwargs, resolved.eval_env_kwargs
            if derived.check_episodes is not None and given["n_eval_episodes"] == ZOO_EVAL_EPISODES:
                given["n_eval_episodes"] = derived.check_episodes
            self.readings_vary = derived.check_episodes is not None
            print(f"sb3-twodrl: {derived.note}", flush=True)
        if given["n_eval_envs"] == SIDE_BY_SIDE:
            given["n_eval_envs"] = given["n_eval_episodes"] if has_batched_env(given["env_id"]) else 1
        super().__init__(**given)
        self.entry, self.batched = entry, batched
        self.goal_checks: GoalCheckCallback | None = None
        self._clock = time.perf_counter()

    def read_hyperparameters(self) -> tuple[dict[str, Any], dict[str, Any]]:
        """rl-zoo3's, or where the constructor was given an ``entry``, that entry (``hyperparams`` over it)."""
        if self.entry is None:
            hyperparams, saved = super().read_hyperparameters()
            if self.ceiling:
                budget = int(float(hyperparams["n_timesteps"]))
                hyperparams["n_timesteps"] = saved["n_timesteps"] = CEILING * budget
                print(
                    f"sb3-twodrl: budget {budget:,} steps; training stops once learned, at most "
                    f"{CEILING * budget:,} steps",
                    flush=True,
                )
            return hyperparams, saved
        hyperparams = resolve(copy.deepcopy(self.entry), None, self.custom_hyperparams).entry
        return hyperparams, OrderedDict(sorted(hyperparams.items()))

    def create_callbacks(self) -> None:
        """rl-zoo3's callbacks, its ``EvalCallback`` a :class:`~sb3_twodrl.callbacks.GoalCheckCallback`."""
        eval_freq, self.eval_freq = self.eval_freq, -1
        super().create_callbacks()
        self.eval_freq = eval_freq
        if self.eval_freq > 0 and not self.optimize_hyperparameters:
            self.eval_freq = max(self.eval_freq // self.n_envs, 1)
            self.goal_checks = GoalCheckCallback(
                self.create_envs(self.n_eval_envs, eval_env=True),
                success_threshold=SUCCESS_THRESHOLD,
                patience=PATIENCE,
                callback_on_new_best=SaveVecNormalizeCallback(save_freq=1, save_path=self.params_path),
                best_model_save_path=self.save_path,
                n_eval_episodes=self.n_eval_episodes,
                log_path=self.save_path,
                eval_freq=self.eval_freq,
                deterministic=self.deterministic_eval,
            )
            self.callbacks.append(self.goal_checks)

    def create_envs(self, n_envs: int, eval_env: bool = False, no_log: bool = False) -> VecEnv:
        """The batch of the registry's vector entry point where there is one and ``batched`` (module docstring), else
        rl-zoo3's."""
        plain = self.env_wrapper is None and self.vec_env_wrapper is None and self.frame_stack is None
        if not (self.batched and plain and self.vec_env_class is DummyVecEnv and has_batched_env(self.env_name.gym_id)):
            return super().create_envs(n_envs, eval_env, no_log)
        options = self.eval_env_kwargs if eval_env else self.env_kwargs
        env: VecEnv = make_train_env(self.env_name.gym_id, n_envs, self.seed, "batched", options)
        log_dir = None if eval_env or no_log else self.save_path
        filename = None if log_dir is None else os.path.join(log_dir, "monitor.csv")
        env = VecMonitor(env, filename, info_keywords=tuple(self.monitor_kwargs.get("info_keywords", ())))
        return self._maybe_normalize(env, eval_env)

    def save_trained_model(self, model: BaseAlgorithm) -> None:
        """rl-zoo3's save (the kept policy, loaded back at the end of training), and :data:`CHECKS_FILE`."""
        super().save_trained_model(model)
        checks = self.goal_checks
        record = {
            "train_s": round(time.perf_counter() - self._clock, 1),
            "num_timesteps": model.num_timesteps,
            "n_timesteps": self.n_timesteps,
            "checks": [] if checks is None else [vars(c) for c in checks.checks],
            "kept": None if checks is None or checks.kept is None else vars(checks.kept),
            "passed": None if checks is None else checks.record.passed,
            "learned_at": None if checks is None else checks.learned_at,
            "threshold": SUCCESS_THRESHOLD,
            "check_episodes": self.n_eval_episodes,
            "check_envs": self.n_eval_envs,
            "readings_vary": self.readings_vary,
            "test_env_kwargs": self.eval_env_kwargs,
        }
        with open(os.path.join(self.save_path, CHECKS_FILE), "w") as f:
            json.dump(record, f, indent=1, default=str)
        SAVED.append(self.save_path)
