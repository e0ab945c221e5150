"""The paper's navigation task (section 3.2, eq. 11-12) as a Gymnasium environment: one robot.

The rules (moves, collisions, evaluations, route codes, the goal) are :mod:`twodrl_envs.nomad.core`'s; the
robot (motion and readings) is a :class:`~twodrl_envs.nomad.core.Robot`. This module holds one robot's
episode state and the Gymnasium API; :mod:`twodrl_envs.nomad.batched` holds N robots' in arrays.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from twodrl_envs.nomad.core import (
    ROUTE_LABELS,
    IdealRobot,
    OfficeCore,
    Robot,
    episode_key,
    office_core,
    remembered_route,
)
from twodrl_envs.nomad.episode import EnvOptions, Episodes, base_key, non_negative, sensor_noise_model
from twodrl_envs.nomad.sensors import NoiseModel
from twodrl_envs.nomad.task import task_facts


def ideal_robot(
    core: OfficeCore,
    generators: Callable[[], Sequence[np.random.Generator]],
    *,
    sensor_noise: bool | NoiseModel | None = None,
    step_sd_cm: float = 0.0,
    slip_sd_cm: float = 0.0,
) -> IdealRobot:
    """The ideal robot of ``NomadOffice-v0`` in ``core``'s office with its options, checked: ``sensor_noise``
    (:func:`~twodrl_envs.nomad.episode.sensor_noise_model`), ``step_sd_cm`` and ``slip_sd_cm`` (finite, >= 0); its
    move noise draws from ``generators()``."""
    noise = sensor_noise_model(sensor_noise)
    step_sd, slip_sd = non_negative("step_sd_cm", step_sd_cm), non_negative("slip_sd_cm", slip_sd_cm)
    return IdealRobot(core, noise, step_sd, slip_sd, generators)


class NomadOfficeEnv(gym.Env):
    """A Nomad 200 searching an office for the goal (paper section 3).

    Actions ``Discrete(4)``: 0 north, 1 east, 2 south, 3 west, 10 cm each, heading fixed north.
    Observation (``observation="sensors"``, the default): 32 normalised readings (16 sonar, then 16 IR;
    see :mod:`twodrl_envs.nomad.sensors`) followed by the normalised odometry position unless
    ``observe_odometry=False``. ``observation="cell"``: ``Discrete(n_cells)``, the index of the robot's
    lattice cell (``core.lattice.cells[i]`` is its centre), the task's Markov state, so that a
    one-hot linear actor and critic are the paper's tables (``docs/tabular.md``); it needs lattice
    motion (no ``step_sd_cm``/``slip_sd_cm``, not ``NomadOfficeReal-v0``) and a start on the lattice.

    Evaluations are eq. 11-12: ``r_R = 5`` on reaching the goal; ``r_P = 1`` on a collision
    (replacing the move cost) and ``0.01`` for every other move, the goal move included. The
    reward is ``r_R - r_P`` (``4.99`` on the goal step) and ``info["punishment"] = r_P``. A
    collision leaves the robot where it was and ends the episode, as does the goal.
    ``info["route"]`` is the route label region the robot's centre entered last (``"shortcut"``/
    ``"detour"``, ``None`` before either); every path from start to goal passes one of them, so at
    the goal it is the route the robot took (the map places them where a robot is committed). A map
    without route regions (no route choice, e.g. ``map="corridor"``) has no ``info["route"]``.

    Ideal model (``NomadOffice-v0``): on the lattice, readings and move outcomes are table
    look-ups; ``sensor_noise`` adds per-step noise. Realistic model (``NomadOfficeReal-v0``):
    ``step_sd_cm`` / ``slip_sd_cm`` perturb each move's length and lateral position, the pose
    leaves the lattice and readings are ray cast at the true pose; odometry reports the
    dead-reckoned (commanded) position, as wheel odometry does.

    The robot is :attr:`robot` (:class:`~twodrl_envs.nomad.core.Robot`): the realistic and replay envs
    are this env with another robot (:attr:`robot_factory`). The options besides ``map`` are
    :class:`~twodrl_envs.nomad.episode.EnvOptions`' (:attr:`options`) and the robot's (here :func:`ideal_robot`'s),
    each checked once, there. The episode's start, moves, observation and ``info`` are
    :class:`~twodrl_envs.nomad.episode.Episodes`' (:attr:`episodes`), on the lattice by its Python fast path,
    which also keeps :class:`~twodrl_envs.nomad.episode.Counters`' counters and time limit of one robot in Python
    values: with ``max_episode_steps`` the step that reaches it returns ``truncated=True`` unless the episode
    terminated, as the batched env's sub-envs do. Without it (``gym.make`` takes ``max_episode_steps`` itself) the
    time limit is that of the ``TimeLimit`` wrapper ``gym.make`` puts around the env (the registered 300 steps, or
    the one given), which flags the same step, a terminating one too.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    robot_factory: ClassVar[Callable[..., Robot]] = ideal_robot
    """Makes the env's robot: ``robot_factory(core, generators, **robot_options)``, its keyword-only parameters the
    env's options besides :class:`~twodrl_envs.nomad.episode.EnvOptions`' (here ``sensor_noise``, ``step_sd_cm``
    and ``slip_sd_cm``: :func:`ideal_robot`)."""

    def __init__(self, map: str | Path | None = None, **options: Any) -> None:
        checked, robot_options = EnvOptions.split(type(self), type(self).robot_factory, options)
        core = office_core(map)
        self._setup(core, type(self).robot_factory(core, self._generators, **robot_options), checked)

    def _generators(self) -> tuple[np.random.Generator]:
        """The generator the ideal robot's move noise draws from: this env's ``np_random``."""
        return (self.np_random,)

    @classmethod
    def deploy_input(cls, map: str | Path | None = None, observe_odometry: bool = True, **_: Any) -> Any:
        """The input stage of an exported policy (``sb3-twodrl-export --input-stage``): the robot's ranges and
        odometry in cm to this env's observation (:class:`~twodrl_envs.nomad.deploy.RawObservation`)."""
        from twodrl_envs.nomad.deploy import RawObservation

        return RawObservation(map, observe_odometry)

    @classmethod
    def task_facts(cls, **options: Any) -> dict[str, Any] | None:
        """The facts of the task of an env made with ``options`` (:func:`twodrl_envs.nomad.task.task_facts`: shortest
        path, farthest start, whether readings vary, the training and test episode options); None on the paper's
        maps, whose task is the registered defaults."""
        own = {key: value for key, value in options.items() if key not in ("starts", "max_episode_steps")}
        return task_facts(cls(**own).robot)

    def _setup(self, core: OfficeCore, robot: Robot, options: EnvOptions) -> None:
        """Spaces and state of an env of ``robot`` in ``core``'s office (every variant's constructor ends here)."""
        self.episodes = Episodes(core, robot, options, type(self).__name__)
        self.core, self.robot, self.options = core, robot, options
        self.observation, self.observe_odometry = options.observation, options.observe_odometry
        self.render_mode, self.starts, self.progress = options.render_mode, options.starts, options.progress
        self.observation_space = self.episodes.observation_space
        self.action_space = spaces.Discrete(4)
        self._outcomes = self.episodes.outcomes.rows if self.episodes.outcomes is not None else []
        self._observe_one, self._info_of = self.episodes.observe_one, self.episodes.info  # bound once: the fast path
        # the counters (Counters' of one robot, in Python values: the fast path) and the time limit (an int: a
        # faster comparison than with math.inf; none: one never reached)
        self._base_key, self._episode, self._key, self._step = 0, -1, 0, 0
        self._limit = sys.maxsize if options.max_episode_steps is None else options.max_episode_steps
        self._cell = core.start_cell
        self._pos = np.array(core.office.start, dtype=np.float64)
        self._odo = self._pos.copy()
        self._route = 0
        self._trajectory: list[tuple[float, float]] = []

    def _counters(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([self._key], dtype=np.uint64), np.array([self._step], dtype=np.int64)

    def _pose_observation(self) -> np.ndarray:
        return self.episodes.observe_poses(self._pos[None], self._odo[None], *self._counters())[0]

    # --- gymnasium API --------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray | int, dict[str, Any]]:
        """Start an episode at ``options["position"] = (x_cm, y_cm)``, else as ``starts`` says (the map's start)."""
        super().reset(seed=seed)
        if seed is not None or self._episode < 0:  # Counters.seed, then Counters.begin, of one robot
            self._base_key, self._episode = base_key(self.np_random), -1
        self._episode += 1
        self._key, self._step = episode_key(self._base_key, self._episode), 0
        options = {} if options is None else options
        if not isinstance(options, dict) or set(options) - {"position"}:
            raise ValueError(f"options may only contain 'position', got {options!r}")
        if "position" in options:
            self._pos, self._cell, self._route = self.episodes.start_state(options["position"])
        else:
            self._pos, self._cell, self._route = self.episodes.start_one(self._key)
        self._odo = self._pos.copy() if self._cell < 0 else self.core.lattice.cells[self._cell]
        self._trajectory = [tuple(self._pos)]
        observation = self._observe_one(self._cell, self._key, 0) if self._cell >= 0 else self._pose_observation()
        position = (float(self._pos[0]), float(self._pos[1]))
        return observation, self._info_of(0.0, False, ROUTE_LABELS[self._route], position, False)

    def step(self, action: Any) -> tuple[np.ndarray | int, float, bool, bool, dict[str, Any]]:
        """Move 10 cm; eq. 11-12 evaluations; terminate on collision or goal, truncate at the time limit."""
        a = int(action)
        if not 0 <= a < 4:
            raise ValueError(f"action must be 0 (N), 1 (E), 2 (S) or 3 (W), got {action!r}")
        self._step += 1
        if self._cell >= 0:
            self._cell, collided, goal, code, reward, punishment = self._outcomes[self._cell][a]
            if not collided:
                self._pos = self._odo = self.core.lattice.cells[self._cell]
            if code:  # the route memory (core.remembered_route) of one robot
                self._route = code
            observation = self._observe_one(self._cell, self._key, self._step)
        else:
            move = self.episodes.move_off_lattice(self._pos[None], self._odo[None], np.array([a]), *self._counters())
            self._pos, self._odo = move.positions[0], move.odometry[0]
            collided, goal = bool(move.collided[0]), bool(move.goal[0])
            reward, punishment = float(move.reward[0]), float(move.punishment[0])
            self._route = int(remembered_route(np.array([self._route]), move.code)[0])
            observation = self._pose_observation()
        if self.render_mode is not None:
            self._trajectory.append(tuple(self._pos))
        info = self._info_of(
            punishment, collided, ROUTE_LABELS[self._route], (float(self._pos[0]), float(self._pos[1])), goal
        )
        if self._step < self._limit:  # the time limit's rule (Counters.truncated) of one robot
            return observation, reward, collided or goal, False, info
        terminated = collided or goal
        return observation, reward, terminated, not terminated, info

    def render(self) -> np.ndarray | None:
        """Top-down RGB frame: walls, start, goal, trajectory, robot and its sonar cones."""
        if self.render_mode != "rgb_array":
            return None
        return self.episodes.frame(self._pos, self._trajectory)
