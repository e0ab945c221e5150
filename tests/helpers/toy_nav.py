"""A scripted stand-in for the Nomad office: episodes whose outcome does not depend on the actions.

It sets the same ``info`` keys as ``twodrl_envs`` (``punishment``, ``route``, ``is_success``, ``collision``,
``position_cm``) and the paper's evaluations, so that the metrics, zoo and reproduction code can be
tested exactly and fast. ``import tests.helpers.toy_nav`` registers ``ToyNav-v0``.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

MOVE, COLLISION, GOAL = 0.01, 1.0, 5.0

# (length, route committed from step 2 on, outcome): outcome in "goal", "collision", "timeout"
SCRIPT: list[tuple[int, str | None, str]] = [
    (3, "shortcut", "goal"),
    (5, "detour", "goal"),
    (2, None, "collision"),
    (4, "shortcut", "collision"),
    (6, None, "timeout"),
]


def expected_episode(spec: tuple[int, str | None, str]) -> tuple[float, int]:
    """Return and length of one scripted episode (scalar reward r_R - r_P)."""
    length, _, outcome = spec
    ret = -MOVE * length
    if outcome == "goal":
        ret += GOAL
    elif outcome == "collision":
        ret -= COLLISION
    return ret, length


class ToyNavEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        script: list[tuple[int, str | None, str]] | None = None,
        random_outcomes: bool = False,
        render_mode: str | None = None,
    ):
        self.render_mode = render_mode
        self.script = script or SCRIPT
        self.random_outcomes = random_outcomes
        self.observation_space = spaces.Box(0.0, 1.0, shape=(3,), dtype=np.float32)
        self.action_space = spaces.Discrete(4)
        self._episode = -1
        self._t = 0
        self._spec = self.script[0]

    def _obs(self) -> np.ndarray:
        length = self._spec[0]
        return np.array([self._t / length, (self._episode % len(self.script)) / len(self.script), 0.5], np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        if seed is not None:
            self._episode = -1
        self._episode += 1
        if self.random_outcomes:
            self._spec = self.script[int(self.np_random.integers(len(self.script)))]
        else:
            self._spec = self.script[self._episode % len(self.script)]
        self._t = 0
        return self._obs(), {"position_cm": (0.0, 0.0), "route": None}

    def render(self):
        frame = np.zeros((32, 32, 3), dtype=np.uint8)
        frame[:, : int(32 * self._t / self._spec[0])] = 255
        return frame

    def step(self, action):
        length, route, outcome = self._spec
        self._t += 1
        last = self._t >= length
        r_r, r_p = 0.0, MOVE
        collision = last and outcome == "collision"
        if collision:
            r_p += COLLISION
        if last and outcome == "goal":
            r_r += GOAL
        info = {
            "punishment": r_p,
            "route": route if self._t >= 2 else None,
            "collision": collision,
            "position_cm": (10.0 * self._t, 0.0),
        }
        terminated = last and outcome in ("goal", "collision")
        truncated = last and outcome == "timeout"
        if terminated or truncated:
            info["is_success"] = outcome == "goal"
        return self._obs(), r_r - r_p, terminated, truncated, info


if "ToyNav-v0" not in gym.registry:
    gym.register("ToyNav-v0", entry_point=ToyNavEnv, max_episode_steps=50)
    gym.register("ToyNavRandom-v0", entry_point=ToyNavEnv, max_episode_steps=50, kwargs={"random_outcomes": True})
