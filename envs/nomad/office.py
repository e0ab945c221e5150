"""The paper's navigation task (section 3.2, eq. 11-12) as a Gymnasium environment."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.geometry import (
    MOVES_CM,
    ROBOT_RADIUS_CM,
    Lattice,
    OfficeMap,
    build_lattice,
    check_goal_reachable,
    clearance,
    is_generated,
    load_map,
    map_source,
    swept_clearance,
)
from twodrl_envs.nomad.sensors import NoiseModel

GOAL_REWARD = 5.0  # r_R, eq. 11
COLLISION_PUNISHMENT = 1.0  # r_P on collision, eq. 12
MOVE_PUNISHMENT = 0.01  # r_P for every (non-colliding) move, eq. 12
ROUTES: tuple[str | None, ...] = (None, "shortcut", "detour")
OBSERVATIONS = ("sensors", "cell")
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


@dataclass(frozen=True)
class OfficeCore:
    """Everything about an office that does not change during learning, computed once per map.

    ``ranges`` ``(n_cells, 32)`` are the exact sensor ranges (cm) of every free lattice cell and
    ``readings`` their normalised, saturated values; ``route_code`` (0 none, 1 shortcut, 2 detour)
    and ``goal`` label cells. A sensor database (MEMORABLE) records noisy readings per cell with
    :meth:`twodrl_envs.nomad.sensors.NoiseModel.sample` of ``ranges``.
    """

    office: OfficeMap
    lattice: Lattice
    ranges: np.ndarray
    readings: np.ndarray
    route_code: np.ndarray
    goal: np.ndarray
    start_cell: int

    def odometry(self, xy: np.ndarray) -> np.ndarray:
        """Position ``(..., 2)`` scaled by the map bounds to [0, 1] (float32)."""
        x0, y0, x1, y1 = self.office.bounds
        return np.clip((xy - (x0, y0)) / (x1 - x0, y1 - y0), 0.0, 1.0).astype(np.float32)


def route_code_at(office: OfficeMap, xy: np.ndarray) -> np.ndarray:
    """Passage code (0 none, 1 shortcut, 2 detour) of centre positions ``(..., 2)``."""
    return np.where(office.in_region("shortcut", xy), 1, np.where(office.in_region("detour", xy), 2, 0))


@cache
def _core(source: str, mtime_ns: int) -> OfficeCore:
    office = load_map(source)
    lattice = build_lattice(office)
    check_goal_reachable(office, lattice)
    ranges = sensors.exact_ranges(office, lattice.cells)
    return OfficeCore(
        office,
        lattice,
        ranges,
        sensors.normalise(ranges),
        route_code_at(office, lattice.cells).astype(np.int8),
        office.in_region("goal", lattice.cells),
        lattice.index(office.start),
    )


def office_core(map_path: str | Path | None = None) -> OfficeCore:
    """The (cached) :class:`OfficeCore` of a map file; ``None`` is the shipped office, ``"generated:SIZE:SEED"``
    a generated one (:mod:`twodrl_envs.nomad.generator`).

    Every env loads its map here: the file is validated (:func:`~twodrl_envs.nomad.geometry.load_map`) and
    its goal must be reachable from the start on the lattice
    (:func:`~twodrl_envs.nomad.geometry.check_goal_reachable`), else ``ValueError``.
    """
    source = map_source(map_path)
    # A generated office never changes; a missing file gets its error from load_map, uncached
    version = -1 if is_generated(source) or not Path(source).exists() else Path(source).stat().st_mtime_ns
    return _core(source, version)


def episode_keys(base: np.ndarray, episode: np.ndarray) -> np.ndarray:
    """Noise key of each episode, derived from a seeded base key and the episode counter."""
    return sensors.counter_hash(base + episode.astype(np.uint64) * _GOLDEN, np.zeros(len(base), dtype=np.int64))[
        :, 0
    ].copy()


_MASK64 = (1 << 64) - 1


def counter_word(key: int, step: int) -> int:
    """Word 0 of :func:`twodrl_envs.nomad.sensors.counter_hash` of one ``(key, step)``, in Python integers.

    A single env needs one word per reset or replayed reading; numpy's call overhead would cost more
    than the hash.
    """
    x = (key + (step * 64 + 1) * int(_GOLDEN)) & _MASK64
    x ^= x >> 30
    x = (x * 0xBF58476D1CE4E5B9) & _MASK64
    x ^= x >> 27
    x = (x * 0x94D049BB133111EB) & _MASK64
    return x ^ (x >> 31)


def episode_key(base: int, episode: int) -> int:
    """:func:`episode_keys` of one env, in Python integers."""
    return counter_word((base + episode * int(_GOLDEN)) & _MASK64, 0)


def _sensor_noise(value: object) -> NoiseModel | None:
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


def _non_negative(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


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

    Sensor-source seam (MEMORABLE): on the lattice, readings come only from
    :meth:`_lattice_readings` and move outcomes only from ``self._moves`` (``(n_cells, 4)``, next
    cell or -1 for a collision). A replay subclass overrides the method to return one of K
    recorded readings of the cell and swaps ``self._moves`` for the recorded free space.
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
    ) -> None:
        if not isinstance(observe_odometry, bool):
            raise TypeError(f"observe_odometry must be a bool, got {observe_odometry!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        self.core = office_core(map)
        self.noise = _sensor_noise(sensor_noise)
        self.step_sd_cm = _non_negative("step_sd_cm", step_sd_cm)
        self.slip_sd_cm = _non_negative("slip_sd_cm", slip_sd_cm)
        self.observation = check_observation(observation, self._on_lattice_motion, type(self).__name__)
        self.observe_odometry = observe_odometry
        self.render_mode = render_mode
        self._moves = self.core.lattice.moves
        self._cell_odometry = self.core.odometry(self.core.lattice.cells)  # on the lattice, odometry is the cell's
        if self.observation == "cell":
            self.observation_space: spaces.Space = spaces.Discrete(len(self.core.lattice.cells))
        else:
            dim = sensors.N_READINGS + (2 if observe_odometry else 0)
            self.observation_space = spaces.Box(0.0, 1.0, shape=(dim,), dtype=np.float32)
        self.action_space = spaces.Discrete(4)
        self._base_key = np.zeros(1, dtype=np.uint64)
        self._episode = -1
        self._key = np.zeros(1, dtype=np.uint64)
        self._step = np.zeros(1, dtype=np.int64)
        self._cell = self.core.start_cell
        self._pos = np.array(self.core.office.start, dtype=np.float64)
        self._odo = self._pos.copy()
        self._route = 0
        self._start: tuple[np.ndarray, int, int] | None = None
        self._trajectory: list[tuple[float, float]] = []
        self._renderer = None

    # --- readings -------------------------------------------------------------------------
    def _lattice_readings(self, cell: int) -> np.ndarray:
        """Normalised readings ``(32,)`` at a lattice cell: table look-up plus per-step noise."""
        if self.noise is None:
            return self.core.readings[cell]
        return sensors.normalise(self.noise.apply(self.core.ranges[cell : cell + 1], self._key, self._step))[0]

    def _pose_readings(self, xy: np.ndarray) -> np.ndarray:
        """Normalised readings ``(32,)`` at an arbitrary pose (ray cast)."""
        ranges = sensors.exact_ranges(self.core.office, xy[None])
        if self.noise is not None:
            ranges = self.noise.apply(ranges, self._key, self._step)
        return sensors.normalise(ranges)[0]

    def _observation(self) -> np.ndarray | int:
        if self.observation == "cell":
            return self._cell
        readings = self._lattice_readings(self._cell) if self._cell >= 0 else self._pose_readings(self._pos)
        if not self.observe_odometry:
            return readings.copy()
        odometry = self._cell_odometry[self._cell] if self._cell >= 0 else self.core.odometry(self._odo)
        return np.concatenate([readings, odometry])

    # --- gymnasium API --------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray | int, dict[str, Any]]:
        """Start an episode at the map's start, or at ``options["position"] = (x_cm, y_cm)``."""
        super().reset(seed=seed)
        if seed is not None or self._episode < 0:
            self._base_key = self.np_random.integers(0, 2**63, size=1, dtype=np.uint64)
            self._episode = -1
        self._episode += 1
        self._key[0] = episode_key(int(self._base_key[0]), self._episode)
        self._step[0] = 0
        options = {} if options is None else options
        if not isinstance(options, dict) or set(options) - {"position"}:
            raise ValueError(f"options may only contain 'position', got {options!r}")
        if "position" in options:
            self._pos, self._cell, self._route = self._start_state(options["position"])
        else:  # the map's start, checked once per env
            if self._start is None:
                self._start = self._start_state(self.core.office.start)
            self._pos, self._cell, self._route = self._start[0].copy(), *self._start[1:]
        self._odo = self._pos.copy() if self._cell < 0 else self.core.lattice.cells[self._cell]
        self._trajectory = [tuple(self._pos)]
        return self._observation(), self._info(False, 0.0)

    def _start_state(self, position: object) -> tuple[np.ndarray, int, int]:
        """Checked position, lattice cell (-1 off the lattice or with noisy motion) and route code of a start."""
        pos = self._check_position(position)
        cell = self.core.lattice.index(pos) if self._on_lattice_motion else -1
        if cell < 0 and self.observation == "cell":
            raise ValueError(f"options['position'] {tuple(pos)} is not a lattice cell, which observation='cell' needs")
        return pos, cell, int(route_code_at(self.core.office, pos))

    @property
    def _on_lattice_motion(self) -> bool:
        return self.step_sd_cm == 0.0 and self.slip_sd_cm == 0.0

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
        self._step[0] += 1
        if self._cell >= 0:
            nxt = int(self._moves[self._cell, a])
            collided = nxt < 0
            if not collided:
                self._cell = nxt
                self._pos = self.core.lattice.cells[nxt]
                self._odo = self._pos
                code = int(self.core.route_code[nxt])
                goal = bool(self.core.goal[nxt])
        else:
            collided, code, goal = self._continuous_move(a)
        if collided:
            punishment, goal = COLLISION_PUNISHMENT, False
        else:
            punishment = MOVE_PUNISHMENT
            if code:
                self._route = code
        if self.render_mode is not None:
            self._trajectory.append(tuple(self._pos))
        reward = (GOAL_REWARD if goal else 0.0) - punishment
        return self._observation(), reward, collided or goal, False, self._info(goal, punishment, collided)

    def _continuous_move(self, action: int) -> tuple[bool, int, bool]:
        command = MOVES_CM[action]
        move = command
        if not self._on_lattice_motion:
            along = self.np_random.normal(0.0, self.step_sd_cm) if self.step_sd_cm else 0.0
            lateral = self.np_random.normal(0.0, self.slip_sd_cm) if self.slip_sd_cm else 0.0
            unit = command / np.linalg.norm(command)
            move = command + along * unit + lateral * np.array([-unit[1], unit[0]])
        target = self._pos + move
        office = self.core.office
        if swept_clearance(self._pos[None], target[None], office.walls)[0] <= ROBOT_RADIUS_CM or not bool(
            office.inside_bounds(target)
        ):
            return True, 0, False
        self._pos = target
        self._odo = self._odo + command
        return False, int(route_code_at(office, target)), bool(office.in_region("goal", target))

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
