"""The paper's navigation task (section 3.2, eq. 11-12) as a Gymnasium environment: one robot.

The rules (moves, collisions, evaluations, route codes, the goal) are :mod:`twodrl_envs.nomad.core`'s; the
robot (motion and readings) is a :class:`~twodrl_envs.nomad.core.Robot`. This module holds one robot's
episode state and the Gymnasium API; :mod:`twodrl_envs.nomad.batched` holds N robots' in arrays.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import (
    ROUTES,
    IdealRobot,
    OfficeCore,
    Robot,
    check_starts,
    continuous_move,
    episode_key,
    evaluations,
    office_core,
    route_code_at,
    start_draw,
)
from twodrl_envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, clearance
from twodrl_envs.nomad.sensors import NoiseModel
from twodrl_envs.nomad.task import task_facts

OBSERVATIONS = ("sensors", "cell")


def sensor_noise_model(value: object) -> NoiseModel | None:
    """The :class:`NoiseModel` of a ``sensor_noise`` option (``True``: the default model; ``None``/``False``: none)."""
    if value is None or value is False:
        return None
    if value is True:
        return NoiseModel()
    if isinstance(value, NoiseModel):
        return value
    raise TypeError(f"sensor_noise must be a bool, None or a NoiseModel, got {type(value).__name__}: {value!r}")


def check_observation(observation: object, lattice: bool, env_name: str) -> str:
    """``observation`` if it is one of :data:`OBSERVATIONS` that ``env_name`` can give, else ``ValueError``.

    ``"cell"`` needs motion on the lattice (``lattice``): elsewhere the robot's pose is no cell.
    """
    if not isinstance(observation, str) or observation not in OBSERVATIONS:
        raise ValueError(f"observation must be one of {OBSERVATIONS}, got {observation!r}")
    if observation == "cell" and not lattice:
        raise ValueError(
            f"observation='cell' needs a robot that moves on the lattice, but {env_name} moves it off the lattice "
            "(use observation='sensors', or the ideal model without step_sd_cm / slip_sd_cm)"
        )
    return observation


def non_negative(name: str, value: object) -> float:
    """``value`` as a float if it is a finite number >= 0, else ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def check_progress(progress: object, robot: Robot) -> float:
    """``progress`` (the weight of the progress signal, :class:`~twodrl_envs.nomad.core.LatticeOutcomes`) as a
    float if it is a finite number >= 0 and, when > 0, ``robot`` moves on the lattice; else ``ValueError``."""
    weight = non_negative("progress", progress)
    if weight > 0.0 and not robot.on_lattice:
        raise ValueError(
            f"progress={progress!r} needs a robot that moves on the lattice ({type(robot).__name__} does not)"
        )
    return weight


def observation_space(core: OfficeCore, observation: str, observe_odometry: bool) -> spaces.Space:
    """One robot's observation space: ``Discrete(n_cells)`` for ``"cell"``, else 32 readings (+ 2 odometry)."""
    if observation == "cell":
        return spaces.Discrete(len(core.lattice.cells))
    return spaces.Box(0.0, 1.0, shape=(sensors.N_READINGS + (2 if observe_odometry else 0),), dtype=np.float32)


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
    are this env with another robot.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        map: str | Path | None = None,
        *,
        observe_odometry: bool = True,
        sensor_noise: bool | NoiseModel | None = None,
        step_sd_cm: float = 0.0,
        slip_sd_cm: float = 0.0,
        render_mode: str | None = None,
        observation: str = "sensors",
        starts: str = "map",
        progress: float = 0.0,
    ) -> None:
        core = office_core(map)
        noise = sensor_noise_model(sensor_noise)
        robot = IdealRobot(core, noise, non_negative("step_sd_cm", step_sd_cm), non_negative("slip_sd_cm", slip_sd_cm))
        self._setup(core, robot, observe_odometry, render_mode, observation, starts, progress)

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

    def _setup(
        self,
        core: OfficeCore,
        robot: Robot,
        observe_odometry: bool,
        render_mode: str | None,
        observation: str,
        starts: str,
        progress: float,
    ) -> None:
        """Spaces and state of an env of ``robot`` in ``core``'s office (every variant's constructor ends here)."""
        if not isinstance(observe_odometry, bool):
            raise TypeError(f"observe_odometry must be a bool, got {observe_odometry!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        self.core, self.robot = core, robot
        self.observation = check_observation(observation, robot.on_lattice, type(self).__name__)
        self.observe_odometry = observe_odometry
        self.render_mode = render_mode
        self.starts = check_starts(starts)
        self._start_cells = robot.start_cells.tolist() if starts == "uniform" else []
        self.observation_space = observation_space(core, observation, observe_odometry)
        self.action_space = spaces.Discrete(4)
        self.progress = check_progress(progress, robot)
        self._outcomes = robot.outcomes(self.progress).rows if robot.on_lattice else []
        self._base_key = 0
        self._episode = -1
        self._key = 0
        self._step = 0
        self._cell = core.start_cell
        self._pos = np.array(core.office.start, dtype=np.float64)
        self._odo = self._pos.copy()
        self._route = 0
        self._start: tuple[np.ndarray, int, int] | None = None
        self._trajectory: list[tuple[float, float]] = []
        self._renderer: Any = None

    def _counters(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([self._key], dtype=np.uint64), np.array([self._step], dtype=np.int64)

    def _observation(self) -> np.ndarray | int:
        if self.observation == "cell":
            return self._cell
        if self._cell >= 0:
            readings = self.robot.cell_reading(self._cell, self._key, self._step)
            odometry = self.core.cell_odometry[self._cell]
        else:
            readings = self.robot.pose_readings(self._pos[None], *self._counters())[0]
            odometry = self.core.odometry(self._odo)
        if not self.observe_odometry:
            return readings.copy()
        return np.concatenate([readings, odometry])

    # --- gymnasium API --------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray | int, dict[str, Any]]:
        """Start an episode at ``options["position"] = (x_cm, y_cm)``, else as ``starts`` says (the map's start)."""
        super().reset(seed=seed)
        if seed is not None or self._episode < 0:
            self._base_key = int(self.np_random.integers(0, 2**63, size=1, dtype=np.uint64)[0])
            self._episode = -1
        self._episode += 1
        self._key = episode_key(self._base_key, self._episode)
        self._step = 0
        options = {} if options is None else options
        if not isinstance(options, dict) or set(options) - {"position"}:
            raise ValueError(f"options may only contain 'position', got {options!r}")
        if "position" in options:
            self._pos, self._cell, self._route = self._start_state(options["position"])
        elif self._start_cells:  # exploring starts: a cell drawn from the episode key
            cell = self._start_cells[start_draw(self._key, len(self._start_cells))]
            self._pos, self._route = self.core.lattice.cells[cell].copy(), int(self.core.route_code[cell])
            self._cell = cell if self.robot.on_lattice else -1
        else:  # the map's start, checked once per env
            if self._start is None:
                self._start = self._start_state(self.core.office.start)
            self._pos, self._cell, self._route = self._start[0].copy(), *self._start[1:]
        self._odo = self._pos.copy() if self._cell < 0 else self.core.lattice.cells[self._cell]
        self._trajectory = [tuple(self._pos)]
        return self._observation(), self._info(False, 0.0)

    def _start_state(self, position: object) -> tuple[np.ndarray, int, int]:
        """Checked position, lattice cell (-1 off the lattice) and route code of a start."""
        pos = self._check_position(position)
        cell = self.core.lattice.index(pos) if self.robot.on_lattice else -1
        self.robot.check_start(pos, cell)
        if cell < 0 and self.observation == "cell":
            raise ValueError(f"options['position'] {tuple(pos)} is not a lattice cell, which observation='cell' needs")
        return pos, cell, int(route_code_at(self.core.office, pos))

    def _check_position(self, position: object) -> np.ndarray:
        try:
            xy = np.asarray(position, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise ValueError(f"options['position'] must be (x_cm, y_cm), got {position!r}") from err
        if xy.shape != (2,) or not np.all(np.isfinite(xy)):
            raise ValueError(f"options['position'] must be two finite numbers (x_cm, y_cm), got {position!r}")
        if not self.core.office.inside_bounds(xy):
            raise ValueError(f"options['position'] {tuple(xy)} is outside the map bounds {self.core.office.bounds}")
        gap = float(clearance(xy[None], self.core.office.walls)[0])
        if gap <= ROBOT_RADIUS_CM:
            raise ValueError(
                f"options['position'] {tuple(xy)} puts the robot in a wall (centre {gap:.1f} cm from a wall, "
                f"radius {ROBOT_RADIUS_CM:.0f} cm)"
            )
        return xy

    def step(self, action: Any) -> tuple[np.ndarray | int, float, bool, bool, dict[str, Any]]:
        """Move 10 cm; eq. 11-12 evaluations; terminate on collision or goal."""
        a = int(action)
        if not 0 <= a < 4:
            raise ValueError(f"action must be 0 (N), 1 (E), 2 (S) or 3 (W), got {action!r}")
        self._step += 1
        if self._cell >= 0:
            self._cell, collided, goal, code, reward, punishment = self._outcomes[self._cell][a]
            if not collided:
                self._pos = self._odo = self.core.lattice.cells[self._cell]
        else:
            actions = np.array([a])
            shift = self.robot.displacement(actions, *self._counters(), [self.np_random])
            target, hit, codes, goals = continuous_move(self.core.office, self._pos[None], shift)
            rewards, punishments = evaluations(hit, goals)
            collided, goal, code = bool(hit[0]), bool(goals[0]), int(codes[0])
            reward, punishment = float(rewards[0]), float(punishments[0])
            if not collided:
                self._pos = target[0]
                self._odo = self._odo + MOVES_CM[a]
        if code:
            self._route = code
        if self.render_mode is not None:
            self._trajectory.append(tuple(self._pos))
        return self._observation(), reward, collided or goal, False, self._info(goal, punishment, collided)

    def _info(self, goal: bool, punishment: float, collided: bool = False) -> dict[str, Any]:
        info = {
            "punishment": punishment,
            "collision": collided,
            "route": ROUTES[self._route],
            "position_cm": (float(self._pos[0]), float(self._pos[1])),
            "is_success": goal,
        }
        if not self.core.office.has_routes:
            del info["route"]
        return info

    def render(self) -> np.ndarray | None:
        """Top-down RGB frame: walls, start, goal, trajectory, robot and its sonar cones."""
        if self.render_mode != "rgb_array":
            return None
        from twodrl_envs.nomad.render import OfficeRenderer

        if self._renderer is None:
            self._renderer = OfficeRenderer(self.core.office)
        return self._renderer.frame(self._pos, self._trajectory)
