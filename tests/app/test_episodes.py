"""twodrl_zoo.evaluation.run_episodes: the one test-episode runner, its order, returns, last infos and goal rate."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium.wrappers import TimeLimit
from stable_baselines3.common.vec_env import DummyVecEnv

from tests.helpers.toy_envs import LatticeCorridor, TwoStateChain
from twodrl_zoo.evaluation import goal_rate, run_episodes


class Scripted:
    """A model whose every sub-env takes one action: 1 (right, to the goal) or 3 (left, into the wall)."""

    def __init__(self, actions: list[int]) -> None:
        self.actions = np.array(actions)
        self.calls = 0

    def predict(self, obs: Any, deterministic: bool = True) -> tuple[np.ndarray, None]:
        self.calls += 1
        return self.actions, None


def test_episodes_sub_env_by_sub_env_with_their_returns_and_last_infos() -> None:
    env = DummyVecEnv([lambda: LatticeCorridor(width=4, height=3)] * 2)
    model = Scripted([1, 3])  # sub-env 0 walks to the goal in 3 steps, sub-env 1 collides at once
    episodes = run_episodes(model, env, per_env=2)
    assert [e.length for e in episodes] == [3, 3, 1, 1]
    assert model.calls == 6  # the batch steps on until sub-env 0 has its two episodes
    assert [e.info["is_success"] for e in episodes] == [True, True, False, False]
    step, goal = float(np.float32(-0.01)), float(np.float32(4.99))  # DummyVecEnv's float32 rewards
    assert episodes[0].episode_return == step * 2 + goal and episodes[2].episode_return == -1
    assert goal_rate(episodes) == 0.5 and goal_rate(episodes[:2]) == 1.0
    assert episodes[2].record.collision is None  # the tracker's record: this env sets no "collision" key


def test_an_env_without_is_success_has_no_goal_rate() -> None:
    env = DummyVecEnv([lambda: TimeLimit(TwoStateChain(), 4)])
    episodes = run_episodes(Scripted([0]), env, per_env=1)
    assert math.isnan(goal_rate(episodes))
