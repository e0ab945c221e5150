"""Tiny environments of the tests' own, each with known dynamics and evaluations."""

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces


class ScriptedFeedbackEnv(gym.Env):
    """Returns a fixed cycle of ``(reward, info)`` pairs, whatever the action; never terminates.

    The observation is the position in the cycle, so that the critics can tell the steps apart.
    """

    def __init__(self, feedback: list[tuple[float, dict[str, Any]]]):
        self.feedback = feedback
        self.observation_space = spaces.Box(0.0, 1.0, shape=(1,), dtype=np.float32)
        self.action_space = spaces.Discrete(2)
        self._t = 0

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self._t = 0
        return np.zeros(1, dtype=np.float32), {}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict]:
        reward, info = self.feedback[self._t % len(self.feedback)]
        self._t += 1
        phase = (self._t % len(self.feedback)) / len(self.feedback)
        return np.array([phase], dtype=np.float32), reward, False, False, dict(info)


class TwoStateChain(gym.Env):
    """States 0 and 1 alternate forever; ``r_R = 1`` in state 0, ``r_P = 1`` in state 1 (``info``)."""

    observation_space = spaces.Box(0.0, 1.0, shape=(2,), dtype=np.float32)
    action_space = spaces.Discrete(2)

    def __init__(self) -> None:
        self._state = 0

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self._state = 0
        return np.eye(2, dtype=np.float32)[0], {}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict]:
        reward_r, reward_p = (1.0, 0.0) if self._state == 0 else (0.0, 1.0)
        self._state = 1 - self._state
        return np.eye(2, dtype=np.float32)[self._state], reward_r - reward_p, False, False, {"punishment": reward_p}


class LatticeCorridor(gym.Env):
    """A small walled lattice with the paper's evaluations (eq. 11-12), position states one-hot.

    The agent starts at the left end of a ``width x height`` room and must reach the right end;
    stepping into the outer wall is a collision and ends the episode.
    """

    moves = np.array([(0, 1), (1, 0), (0, -1), (-1, 0)])

    def __init__(self, width: int = 6, height: int = 3):
        self.width, self.height = width, height
        self.observation_space = spaces.Box(0.0, 1.0, shape=(width * height,), dtype=np.float32)
        self.action_space = spaces.Discrete(4)
        self.start = np.array([0, height // 2])
        self.goal = np.array([width - 1, height // 2])
        self._pos = self.start.copy()

    def _obs(self) -> np.ndarray:
        obs = np.zeros(self.width * self.height, dtype=np.float32)
        obs[self._pos[1] * self.width + self._pos[0]] = 1.0
        return obs

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self._pos = self.start.copy()
        return self._obs(), {}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict]:
        new = self._pos + self.moves[int(action)]
        collision = not (0 <= new[0] < self.width and 0 <= new[1] < self.height)
        if not collision:
            self._pos = new
        goal = bool((self._pos == self.goal).all())
        reward_r = 5.0 if goal else 0.0
        reward_p = 1.0 if collision else 0.01
        info = {"punishment": reward_p, "is_success": goal}
        return self._obs(), reward_r - reward_p, collision or goal, False, info
