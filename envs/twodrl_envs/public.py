"""Public tasks with an explicit punishment stream, for the benchmark (docs/public_tasks.md).

Each wrapper keeps the convention of ``reward_split="info"``: the scalar reward is the net
``r_R - r_P`` and ``info["punishment"]`` holds ``r_P >= 0``, so a stock algorithm and a 2D-RL
algorithm see the same scalar reward. Each also writes the episode's punishment events so far
(``info["crash"]``, ``info["cliff_falls"]``, ``info["lava"]``) at every step, which a ``Monitor``
with ``info_keywords`` records per episode.

- :class:`LunarLanderSplit`: crash and fuel are punishment, landing and shaping reward; the scalar
  reward is LunarLander's own, unchanged;
- :class:`CliffWalkingSplit`: the cliff's -100 is a step cost of -1 (reward stream) plus a
  punishment of 99; the scalar reward is CliffWalking's own, unchanged;
- :class:`LavaSplit`: MiniGrid's lava ends the episode with reward 0; here it is punished by 1, so
  the scalar reward of a lava step becomes -1 (for both arms: a change of the task, documented).
"""

from __future__ import annotations

from typing import Any, SupportsFloat

import gymnasium as gym

MAIN_ENGINE_COST = 0.30
"""LunarLander's reward per step of the main engine (``m_power * 0.30``, discrete: ``m_power = 1``)."""
SIDE_ENGINE_COST = 0.03
"""LunarLander's reward per step of a side engine."""
CRASH_REWARD = -100.0
CLIFF_REWARD = -100.0
STEP_REWARD = -1.0
CLIFF_MAX_EPISODE_STEPS = 100
"""CliffWalking has no time limit of its own; 100 steps is ~7 times the 13-step shortest path."""


class LunarLanderSplit(gym.Wrapper):
    """Discrete LunarLander with ``info["punishment"]``: 100 on a crash step, else the step's fuel cost.

    The scalar reward is unchanged. LunarLander's reward is ``shaping - 0.3 main - 0.03 side`` on a
    step that does not end the episode and exactly ``-100`` (crash or out of bounds) or ``+100``
    (landed, at rest) on the last one, so ``r_P = 0.3 main + 0.03 side`` (fuel) or 100 (crash) and
    ``r_R = reward + r_P`` (shaping, or the landing's +100). This is mo-lunar-lander-v3's reward
    vector ``(landed/crashed, shaping, -main, -side)`` with weights ``(1, 1, 0.3, 0.03)`` on every
    step but the last; on the last, MO keeps that step's shaping and fuel, which the scalar drops.
    """

    def __init__(self, env: gym.Env):
        if getattr(env.unwrapped, "continuous", False):
            raise ValueError("env: LunarLanderSplit needs the discrete LunarLander (continuous=False)")
        super().__init__(env)
        self._crash = 0

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        self._crash = 0
        obs, info = self.env.reset(**kwargs)
        return obs, {**info, "punishment": 0.0, "crash": 0}

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated and float(reward) == CRASH_REWARD:
            self._crash, punishment = 1, -CRASH_REWARD
        elif terminated:
            punishment = 0.0
        else:
            punishment = MAIN_ENGINE_COST if int(action) == 2 else SIDE_ENGINE_COST if int(action) in (1, 3) else 0.0
        return obs, reward, terminated, truncated, {**info, "punishment": punishment, "crash": self._crash}


class CliffWalkingSplit(gym.Wrapper):
    """CliffWalking with ``info["punishment"] = 99`` on a step into the cliff (``r_R = -1`` on every step).

    The scalar reward is unchanged (-1 a step, -100 into the cliff, which sends the agent back to
    the start). ``info["cliff_falls"]``: the episode's falls so far.
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        self._falls = 0

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        self._falls = 0
        obs, info = self.env.reset(**kwargs)
        return obs, {**info, "punishment": 0.0, "cliff_falls": 0}

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        fell = float(reward) == CLIFF_REWARD
        self._falls += fell
        punishment = STEP_REWARD - CLIFF_REWARD if fell else 0.0
        return obs, reward, terminated, truncated, {**info, "punishment": punishment, "cliff_falls": self._falls}


class LavaSplit(gym.Wrapper):
    """MiniGrid with lava punished: a step into lava has reward -1 (MiniGrid: 0) and ``info["punishment"] = 1``.

    ``info["lava"]``: 1 once the episode has ended in lava.
    """

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        return obs, {**info, "punishment": 0.0, "lava": 0}

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        base: Any = self.env.unwrapped  # a MiniGrid env: its grid and the agent's position
        cell = base.grid.get(*base.agent_pos)
        lava = int(terminated and cell is not None and cell.type == "lava")
        return obs, float(reward) - lava, terminated, truncated, {**info, "punishment": float(lava), "lava": lava}


def make_lunar_lander(**kwargs: Any) -> gym.Env:
    return LunarLanderSplit(gym.make("LunarLander-v3", **kwargs))


def make_cliff_walking(**kwargs: Any) -> gym.Env:
    return CliffWalkingSplit(gym.make("CliffWalking-v1", max_episode_steps=CLIFF_MAX_EPISODE_STEPS, **kwargs))


def make_lava_gap(**kwargs: Any) -> gym.Env:
    import minigrid  # noqa: F401  (registers the MiniGrid IDs)

    return LavaSplit(gym.make("MiniGrid-LavaGapS7-v0", **kwargs))
