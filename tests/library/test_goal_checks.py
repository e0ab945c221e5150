"""Training keeps what worked: GoalCheckCallback keeps the policy of the best goal check and stops once learned."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from stable_baselines3 import A2C
from stable_baselines3.common.callbacks import BaseCallback

from sb3_twodrl import TwoDimA2C
from sb3_twodrl.callbacks import GoalCheckCallback

EVAL_EPISODES = 2
STEPS_PER_CHECK = 5


class ScheduledGoal(gym.Env):
    """One-step episodes of return 1; the k-th group of ``EVAL_EPISODES`` episodes reaches the goal as
    ``schedule[k]`` says (1: all, 0.5: the first of the group, 0: none), whatever the policy: the checks' goal
    rates are set here."""

    observation_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
    action_space = spaces.Discrete(2)

    def __init__(self, schedule: list[float] | None = None, reports: bool = True) -> None:
        self.schedule, self.reports, self.episodes = schedule or [], reports, 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        return np.ones(1, np.float32), {}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        group, index = divmod(self.episodes, EVAL_EPISODES)
        self.episodes += 1
        rate = self.schedule[min(group, len(self.schedule) - 1)] if self.schedule else 0.0
        info = {"is_success": index < rate * EVAL_EPISODES} if self.reports else {}
        return np.ones(1, np.float32), 1.0, True, False, info


class Snapshots(BaseCallback):
    """The policy's parameters at each check (every ``STEPS_PER_CHECK`` calls), after the check ran."""

    def __init__(self) -> None:
        super().__init__()
        self.states: list[dict[str, th.Tensor]] = []

    def _on_step(self) -> bool:
        if self.n_calls % STEPS_PER_CHECK == 0:
            self.states.append({k: v.clone() for k, v in self.model.policy.state_dict().items()})
        return True


def _train(schedule: list[float], budget: int, patience: int = 2, **kwargs: Any) -> tuple[Any, Any, Snapshots]:
    model = A2C("MlpPolicy", ScheduledGoal(), n_steps=STEPS_PER_CHECK, learning_rate=0.1, seed=0, device="cpu")
    checks = GoalCheckCallback(
        ScheduledGoal(schedule, **kwargs), eval_freq=STEPS_PER_CHECK, n_eval_episodes=EVAL_EPISODES, patience=patience
    )
    snapshots = Snapshots()
    model.learn(budget, callback=[checks, snapshots])
    return model, checks, snapshots


def _same(a: dict[str, th.Tensor], b: dict[str, th.Tensor]) -> bool:
    return all(th.equal(a[k], b[k]) for k in a)


def test_the_model_ends_with_the_policy_of_the_best_check_not_the_last() -> None:
    model, checks, snapshots = _train([0.0, 1.0, 0.5, 0.0], budget=4 * STEPS_PER_CHECK)
    assert [c.goal_rate for c in checks.checks] == [0.0, 1.0, 0.5, 0.0]
    assert checks.kept is not None and checks.kept.timesteps == 2 * STEPS_PER_CHECK and checks.learned_at is None
    final = model.policy.state_dict()
    assert _same(final, snapshots.states[1]) and not _same(snapshots.states[1], snapshots.states[3])


def test_saved_and_loaded_model_is_the_kept_policy(tmp_path: Any) -> None:
    model, _, snapshots = _train([1.0, 0.0, 0.0], budget=3 * STEPS_PER_CHECK)
    model.save(tmp_path / "model")
    assert _same(A2C.load(tmp_path / "model", device="cpu").policy.state_dict(), snapshots.states[0])


def test_training_stops_once_patience_checks_in_a_row_pass() -> None:
    model, checks, _ = _train([0.0, 1.0, 0.5, 1.0, 1.0, 1.0], budget=100 * STEPS_PER_CHECK)
    assert checks.learned_at == 5 * STEPS_PER_CHECK and model.num_timesteps == 5 * STEPS_PER_CHECK
    assert checks.kept is not None and checks.kept.timesteps == 5 * STEPS_PER_CHECK  # ties: the later check


def test_an_env_without_is_success_keeps_nothing_and_says_so() -> None:
    with pytest.warns(UserWarning, match="is_success"):
        model, checks, _ = _train([1.0], budget=3 * STEPS_PER_CHECK, reports=False)
    assert checks.kept is None and checks.checks == [] and model.num_timesteps == 3 * STEPS_PER_CHECK


def test_works_with_the_two_dimensional_algorithms() -> None:
    model = TwoDimA2C("MlpPolicy", ScheduledGoal(), n_steps=STEPS_PER_CHECK, seed=0, device="cpu")
    checks = GoalCheckCallback(ScheduledGoal([0.0, 1.0, 1.0]), eval_freq=STEPS_PER_CHECK, n_eval_episodes=2)
    model.learn(50 * STEPS_PER_CHECK, callback=checks)
    assert checks.learned_at == 3 * STEPS_PER_CHECK == model.num_timesteps


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"success_threshold": 0.0}, "success_threshold"), ({"success_threshold": 1.5}, "success_threshold"),
     ({"patience": 0}, "patience"), ({"patience": 1.5}, "patience"), ({"patience": True}, "patience")],
)  # fmt: skip
def test_bad_arguments_name_themselves(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        GoalCheckCallback(ScheduledGoal(), **kwargs)
