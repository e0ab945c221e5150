"""The robot-side loop without a robot: a stand-in robot driven as a deployed policy drives a real Nomad.

On the robot (docs/own_office.md, "Deploy"), an exported policy reads what the robot measures, the 16 sonar and
16 infrared ranges and the odometry in cm, and commands 10 cm moves until the goal. :class:`StandInRobot` offers
those functions on any Nomad env ID, the stand-in robots ``NomadOfficeReal-v0`` and ``NomadOfficeMuJoCo-v0``
included, so that the same loop runs, unchanged, in simulation::

    robot = StandInRobot("NomadOfficeMuJoCo-v0", map="my_office.json", seed=0)
    while not robot.ended():
        raw = np.concatenate([robot.sonar_cm(), robot.ir_cm(), robot.odometry_cm()])[None]  # (1, 34) float64
        robot.move_10cm(int(policy.run(["action"], {"obs": raw})[0][0]))

The ranges are the env's readings as the robot reports them (saturated to the sensors' ranges), the odometry its
dead reckoning, both in cm, read back from the env's float32 observation (so to a few micrometres); through the
input stage (:class:`~twodrl_envs.nomad.deploy.RawObservation`) they give
the env's observation bit for bit (tested), so the loop makes the decisions an env episode makes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import load_env_creator

from twodrl_envs.nomad import sensors

OBSERVATION_SIZE = sensors.N_READINGS + 2


class StandInRobot:
    """One episode at a time of ``env_id`` (any Nomad ID) on ``map``, from the map's start, seeded ``seed``.

    ``options`` go to ``gym.make`` (e.g. ``model=`` of ``NomadOfficeReal-v0``); the odometry is always observed.
    The episode's time limit is the map's (:attr:`time_limit`: the env's task facts, e.g. 480 steps
    on an office whose farthest start is 160 moves; the registered 300 on the paper's maps) unless ``options``
    give ``max_episode_steps``. A move after the goal, a collision or the time limit is a ``RuntimeError``
    (:meth:`ended` says when); :meth:`reset` starts again.
    """

    def __init__(
        self, env_id: str = "NomadOfficeReal-v0", *, map: str | Path | None = None, seed: int | None = 0, **options: Any
    ) -> None:
        if not isinstance(env_id, str) or env_id not in gym.registry:
            raise ValueError(f"env_id must be a registered Nomad env ID (e.g. 'NomadOfficeReal-v0'), got {env_id!r}")
        if "observe_odometry" in options or "observation" in options:
            raise ValueError("StandInRobot observes the sensors and the odometry: observe_odometry and observation")
        if map is not None:
            options["map"] = map
        if "max_episode_steps" not in options:
            facts = self._task_facts(env_id, options)
            if facts is not None:
                options["max_episode_steps"] = facts["time_limit"]
        self.env = gym.make(env_id, disable_env_checker=True, **options)
        self.time_limit: int = self.env.spec.max_episode_steps  # type: ignore[union-attr,assignment]
        """The most moves of an episode (the test time limit); a move past it is refused."""
        space = self.env.observation_space
        if not isinstance(space, gym.spaces.Box) or space.shape != (OBSERVATION_SIZE,):
            raise ValueError(f"env_id {env_id!r} is not a Nomad env: its observations are {space}")
        x0, y0, x1, y1 = self.env.unwrapped.core.office.bounds  # type: ignore[attr-defined]
        self._origin, self._extent = np.array([x0, y0]), np.array([x1 - x0, y1 - y0])
        self._span = sensors.HIGH_CM - sensors.LOW_CM
        self.reset(seed)

    @staticmethod
    def _task_facts(env_id: str, options: dict[str, Any]) -> dict[str, Any] | None:
        """The facts the env's class states of its task with ``options`` (None: the registered defaults are it)."""
        spec = gym.registry[env_id]
        creator = load_env_creator(spec.entry_point) if isinstance(spec.entry_point, str) else spec.entry_point
        state = getattr(creator, "task_facts", None)
        facts = None if state is None else state(**{**spec.kwargs, **options})
        return facts if isinstance(facts, dict) else None

    def reset(self, seed: int | None = None) -> None:
        """Put the robot back at the map's start; a new episode (``seed`` as ``Env.reset``'s)."""
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)):
            raise TypeError(f"seed must be an int or None, got {type(seed).__name__}: {seed!r}")
        observation, self._info = self.env.reset(seed=None if seed is None else int(seed))
        self._observation = np.asarray(observation)
        self._ended = ""
        self.moves = 0

    def _ranges(self) -> np.ndarray:
        return sensors.LOW_CM + self._observation[: sensors.N_READINGS].astype(np.float64) * self._span

    def sonar_cm(self) -> np.ndarray:
        """The 16 sonar ranges ``(16,)`` cm, sensor ``i`` at ``i * 22.5`` degrees counter-clockwise from north."""
        return self._ranges()[: sensors.N_SONAR]

    def ir_cm(self) -> np.ndarray:
        """The 16 infrared ranges ``(16,)`` cm, in the sonar's order."""
        return self._ranges()[sensors.N_SONAR :]

    def odometry_cm(self) -> np.ndarray:
        """The odometry ``(x, y)`` ``(2,)`` cm in the map's frame (dead reckoning, as the robot reports it)."""
        return self._origin + self._observation[sensors.N_READINGS :].astype(np.float64) * self._extent

    def move_10cm(self, action: int) -> None:
        """Command a 10 cm move: 0 north, 1 east, 2 south, 3 west."""
        if isinstance(action, bool) or not isinstance(action, int | np.integer) or not 0 <= action < 4:
            raise ValueError(f"action must be 0 (N), 1 (E), 2 (S) or 3 (W), got {action!r}")
        if self._ended:
            raise RuntimeError(f"the episode has ended ({self._ended}); reset() puts the robot back at the start")
        observation, _, terminated, truncated, self._info = self.env.step(int(action))
        self._observation = np.asarray(observation)
        self.moves += 1
        if self._info["collision"]:
            self._ended = f"the robot collided after {self.moves} moves"
        elif self._info["is_success"]:
            self._ended = f"the robot reached the goal in {self.moves} moves"
        elif terminated or truncated:
            self._ended = f"the time limit, {self.moves} moves"

    move = move_10cm

    def ended(self) -> bool:
        """Whether the episode is over: the goal reached, a collision, or :attr:`time_limit` moves made."""
        return bool(self._ended)

    def at_goal(self) -> bool:
        """Whether the last move reached the goal."""
        return bool(self._info["is_success"])

    def collided(self) -> bool:
        """Whether the last move touched a wall (the robot stays where it was; the episode is over)."""
        return bool(self._info["collision"])

    def position_cm(self) -> tuple[float, float]:
        """The robot's true position (cm): what the simulation knows and the robot does not."""
        return self._info["position_cm"]
