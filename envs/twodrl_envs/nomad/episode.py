"""An office episode written once, for one robot or N: the options and their checks, the counters and the time
limit, the start, a move, the route memory, the observation, ``info`` and the frame.

:class:`EnvOptions` are the options every Nomad env takes (``gym.make(id, **options)``), checked once.
:class:`Episodes` applies :mod:`twodrl_envs.nomad.core`'s rules to the robots of an env in arrays ``(n, ...)``,
and :class:`Counters` counts their episodes and steps and truncates them at the time limit, as MiniGrid's
``MiniGridEnv.step()`` counts and truncates; :class:`~twodrl_envs.nomad.batched.BatchedNomadOffice` holds N
robots' state and calls them, and :class:`~twodrl_envs.nomad.office.NomadOfficeEnv` holds one robot's. On the
lattice the single env takes a Python fast path (:meth:`Episodes.start_one`, :meth:`Episodes.observe_one`,
its counters, :attr:`LatticeOutcomes.rows <twodrl_envs.nomad.core.LatticeOutcomes.rows>`), measured faster
than arrays of one row and tested equal to them.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import InitVar, dataclass, fields
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import VectorEnv

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import (
    OfficeCore,
    Robot,
    check_starts,
    continuous_move,
    episode_keys,
    evaluations,
    route_code_at,
    start_draw,
    start_draws,
)
from twodrl_envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, clearance
from twodrl_envs.nomad.sensors import NoiseModel

OBSERVATIONS = ("sensors", "cell")
INFO_KEYS = ("punishment", "collision", "route", "position_cm", "is_success")
"""Keys of every step's ``info`` (``route`` only on a map with route regions)."""
RENDER_MODES = ("rgb_array",)


def sensor_noise_model(value: object) -> NoiseModel | None:
    """The :class:`NoiseModel` of a ``sensor_noise`` option (``True``: the default model; ``None``/``False``: none)."""
    if value is None or value is False:
        return None
    if value is True:
        return NoiseModel()
    if isinstance(value, NoiseModel):
        return value
    raise TypeError(f"sensor_noise must be a bool, None or a NoiseModel, got {type(value).__name__}: {value!r}")


def check_observation(observation: str, lattice: bool, env_name: str) -> None:
    """``ValueError`` if ``env_name`` cannot give ``observation``: ``"cell"`` needs motion on the lattice
    (``lattice``), elsewhere the robot's pose is no cell."""
    if observation == "cell" and not lattice:
        raise ValueError(
            f"observation='cell' needs a robot that moves on the lattice, but {env_name} moves it off the lattice "
            "(use observation='sensors', or the ideal model without step_sd_cm / slip_sd_cm)"
        )


def non_negative(name: str, value: object) -> float:
    """``value`` as a float if it is a finite number >= 0, else ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def check_progress(progress: float, robot: Robot) -> None:
    """``ValueError`` if ``progress`` (the weight of the progress signal,
    :class:`~twodrl_envs.nomad.core.LatticeOutcomes`) is > 0 and ``robot`` does not move on the lattice."""
    if progress > 0.0 and not robot.on_lattice:
        raise ValueError(
            f"progress={progress!r} needs a robot that moves on the lattice ({type(robot).__name__} does not)"
        )


@dataclass(frozen=True)
class EnvOptions:
    """The options every Nomad env takes besides ``map`` and its robot's (``gym.make(id, **options)``, and
    ``gym.make_vec`` for the batched envs), checked here, once, when made (:meth:`split`).

    ``observe_odometry``: the normalised odometry after the 32 readings; ``render_mode``: None or one of the
    env's ``metadata["render_modes"]`` (``render_modes``, not an option); ``observation``: one of
    :data:`OBSERVATIONS`; ``starts``: one of :data:`~twodrl_envs.nomad.core.STARTS`; ``progress``: the weight of
    the progress signal (a float >= 0); ``max_episode_steps``: the env's own time limit, the step that reaches it
    truncating an episode that did not terminate (:class:`Counters`). ``None``: a single env has none of its own
    (``gym.make`` takes ``max_episode_steps`` and wraps the ID's registered limit, or that one, around it:
    ``TimeLimit``, which flags the same step), a batched env the registered one
    (:data:`~twodrl_envs.MAX_EPISODE_STEPS`, which ``gym.make_vec`` passes). The checks that depend on the robot
    (``"cell"`` and ``progress`` need the lattice) are :class:`Episodes`'.
    """

    observe_odometry: bool = True
    render_mode: str | None = None
    observation: str = "sensors"
    starts: str = "map"
    progress: float = 0.0
    max_episode_steps: int | None = None
    render_modes: InitVar[Sequence[str]] = RENDER_MODES

    def __post_init__(self, render_modes: Sequence[str]) -> None:
        if not isinstance(self.observe_odometry, bool):
            raise TypeError(f"observe_odometry must be a bool, got {self.observe_odometry!r}")
        if self.render_mode is not None and self.render_mode not in render_modes:
            raise ValueError(f"render_mode must be None or one of {list(render_modes)}, got {self.render_mode!r}")
        if not isinstance(self.observation, str) or self.observation not in OBSERVATIONS:
            raise ValueError(f"observation must be one of {OBSERVATIONS}, got {self.observation!r}")
        check_starts(self.starts)
        object.__setattr__(self, "progress", non_negative("progress", self.progress))
        limit = self.max_episode_steps
        if limit is not None and (isinstance(limit, bool) or not isinstance(limit, int) or limit < 1):
            raise ValueError(f"max_episode_steps must be a positive int, got {limit!r}")

    @classmethod
    def split(
        cls, env: type[gym.Env] | type[VectorEnv], robot_factory: Callable[..., Robot], options: Mapping[str, Any]
    ) -> tuple[EnvOptions, dict[str, Any]]:
        """The keyword arguments ``options`` of an ``env`` class's constructor, split: its :class:`EnvOptions`,
        checked (its render modes its ``metadata``'s), and the options of its robot, the keyword-only parameters
        of ``robot_factory`` (which checks them).

        :raises TypeError: naming a keyword that is neither, as Python names an unexpected keyword argument
        """
        own = {option.name for option in fields(cls)}
        parameters = inspect.signature(robot_factory).parameters.values()
        robot = {parameter.name for parameter in parameters if parameter.kind is inspect.Parameter.KEYWORD_ONLY}
        for name in options:
            if name not in own | robot:
                raise TypeError(f"{env.__name__}.__init__() got an unexpected keyword argument {name!r}")
        checked = cls(**{name: options[name] for name in own & set(options)}, render_modes=env.metadata["render_modes"])
        return checked, {name: options[name] for name in robot & set(options)}


def observation_space(core: OfficeCore, observation: str, observe_odometry: bool) -> spaces.Space:
    """One robot's observation space: ``Discrete(n_cells)`` for ``"cell"``, else 32 readings (+ 2 odometry)."""
    if observation == "cell":
        return spaces.Discrete(len(core.lattice.cells))
    return spaces.Box(0.0, 1.0, shape=(sensors.N_READINGS + (2 if observe_odometry else 0),), dtype=np.float32)


def base_key(rng: np.random.Generator) -> int:
    """An env's noise base key, drawn from its seeded generator (the episode keys derive from it)."""
    return int(rng.integers(0, 2**63, size=1, dtype=np.uint64)[0])


class Start(NamedTuple):
    """Where episodes start: lattice cells ``(n,)`` (-1 off the lattice), centres ``(n, 2)`` cm, route codes ``(n,)``;
    at the map's start, one cell, centre and code that broadcast to them."""

    cells: np.ndarray | int
    positions: np.ndarray
    routes: np.ndarray | int


class Move(NamedTuple):
    """The outcome of moves ``(n,)``: cells, centres ``(n, 2)`` and odometry ``(n, 2)`` after them (where a move
    collides, those before it), ``collided``, ``goal``, route ``code`` and the evaluations (eq. 11-12)."""

    cells: np.ndarray
    positions: np.ndarray
    odometry: np.ndarray
    collided: np.ndarray
    goal: np.ndarray
    code: np.ndarray
    reward: np.ndarray
    punishment: np.ndarray


class Counters:
    """The counters of ``n`` robots' episodes, arrays ``(n,)``, kept as MiniGrid's ``MiniGridEnv.step()`` keeps its
    step count: ``base`` keys drawn from each robot's seeded generator, ``episode`` numbers since the seeding, the
    episode's noise ``keys`` (derived from both) and the ``steps`` taken in it; ``limit`` is the time limit
    (``inf``: none). The single env keeps one robot's in Python values (its fast path), tested equal."""

    def __init__(self, n: int, max_episode_steps: int | None) -> None:
        self.base = np.zeros(n, dtype=np.uint64)
        self.episode = np.full(n, -1, dtype=np.int64)
        self.keys = np.zeros(n, dtype=np.uint64)
        self.steps = np.zeros(n, dtype=np.int64)
        self.limit = math.inf if max_episode_steps is None else max_episode_steps

    def seed(self, rngs: Sequence[np.random.Generator], rows: np.ndarray | None = None) -> None:
        """Draw the base key of each robot of ``rows`` (a bool mask; all by default) from its seeded generator, in
        ``rngs`` (one per robot of ``rows``); its next episode is its first."""
        rows = np.ones(len(self.base), dtype=bool) if rows is None else rows
        self.base[rows] = [base_key(rng) for rng in rngs]
        self.episode[rows] = -1

    def begin(self, rows: np.ndarray) -> None:
        """Count a new episode of the robots ``rows`` (a bool mask): its number, its noise key, no steps yet."""
        self.episode[rows] += 1
        self.keys[rows] = episode_keys(self.base[rows], self.episode[rows])
        self.steps[rows] = 0

    def truncated(self, terminated: np.ndarray) -> np.ndarray:
        """Gymnasium's ``truncated`` after a step (counted in :attr:`steps`): the step that reaches the time limit
        truncates an episode that did not terminate."""
        return (self.steps >= self.limit) & ~terminated


class Episodes:
    """The episodes of ``robot`` in ``core``'s office with an env's checked ``options`` (the single and batched
    envs'); ``env_name`` names the env in errors. Here are the checks of the options that depend on the robot
    (``observation="cell"`` and ``progress`` > 0 need the lattice).
    Odometry off the lattice is dead reckoning: the start plus the commanded moves that did not collide.
    """

    def __init__(self, core: OfficeCore, robot: Robot, options: EnvOptions, env_name: str = "the env") -> None:
        check_observation(options.observation, robot.on_lattice, env_name)
        check_progress(options.progress, robot)
        self.core, self.robot, self.options = core, robot, options
        self.observe_odometry, self.observation = options.observe_odometry, options.observation
        self.starts, self.progress = options.starts, options.progress
        self.outcomes = robot.outcomes(self.progress) if robot.on_lattice else None
        self.start_cells = robot.start_cells if self.starts == "uniform" else np.zeros(0, dtype=np.intp)
        self._start_cells = self.start_cells.tolist()
        self.observation_space = observation_space(core, self.observation, self.observe_odometry)
        self.has_routes = core.office.has_routes
        self.info_keys = tuple(key for key in INFO_KEYS if key != "route" or self.has_routes)
        # set here, not by cached_property: an attribute added later slows every attribute look-up (the fast path's)
        self._map_start: tuple[np.ndarray, int, int] | None = None
        self._renderer: Any = None

    # --- the start ----------------------------------------------------------------------------
    def start_state(self, position: object) -> tuple[np.ndarray, int, int]:
        """Checked position ``(2,)``, lattice cell (-1 off the lattice) and route code of a start at ``position``."""
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

    def map_start(self) -> tuple[np.ndarray, int, int]:
        """:meth:`start_state` of the map's start, checked on first use."""
        if self._map_start is None:
            self._map_start = self.start_state(self.core.office.start)
        return self._map_start

    def start(self, keys: np.ndarray) -> Start:
        """The starts of episodes of noise keys ``keys`` ``(n,)``, as ``starts`` says: the map's start, or a cell of
        :attr:`start_cells` drawn from the key (exploring starts)."""
        if self.starts == "uniform":
            drawn = self.start_cells[start_draws(keys, len(self.start_cells))]
            cells = drawn if self.robot.on_lattice else np.full(len(keys), -1)
            return Start(cells, self.core.lattice.cells[drawn], self.core.route_code[drawn])
        position, cell, route = self.map_start()
        return Start(cell, position, route)

    def start_one(self, key: int) -> tuple[np.ndarray, int, int]:
        """:meth:`start` of one episode in Python values: position ``(2,)`` (a fresh array), cell and route code."""
        if self._start_cells:
            drawn = self._start_cells[start_draw(key, len(self._start_cells))]
            cell = drawn if self.robot.on_lattice else -1
            return self.core.lattice.cells[drawn].copy(), cell, int(self.core.route_code[drawn])
        position, cell, route = self.map_start()
        return position.copy(), cell, route

    # --- a move -------------------------------------------------------------------------------
    def move(
        self,
        cells: np.ndarray,
        positions: np.ndarray,
        odometry: np.ndarray,
        actions: np.ndarray,
        keys: np.ndarray,
        steps: np.ndarray,
    ) -> Move:
        """The moves ``actions`` ``(n,)`` of robots at ``cells``/``positions`` with ``odometry``, at counters
        ``keys``/``steps`` (the step being taken): by the lattice outcomes on the lattice, else by the robot's
        displacement and :func:`~twodrl_envs.nomad.core.continuous_move`. On the lattice the odometry is the
        position."""
        if self.outcomes is None:
            return self.move_off_lattice(positions, odometry, actions, keys, steps)
        out = self.outcomes
        after = out.next_cell[cells, actions]
        moved = self.core.lattice.cells[after]
        taken = (cells, actions)
        return Move(
            after,
            moved,
            moved,
            out.collided[taken],
            out.goal[taken],
            out.code[taken],
            out.reward[taken],
            out.punishment[taken],
        )

    def move_off_lattice(
        self, positions: np.ndarray, odometry: np.ndarray, actions: np.ndarray, keys: np.ndarray, steps: np.ndarray
    ) -> Move:
        """:meth:`move` of robots off the lattice's cells (cells -1): the robot's displacement, the swept-disc test,
        dead-reckoned odometry."""
        shift = self.robot.displacement(actions, keys, steps)
        target, collided, code, goal = continuous_move(self.core.office, positions, shift)
        reward, punishment = evaluations(collided, goal)
        stay = collided[:, None]
        moved = np.where(stay, positions, target)
        odometry = np.where(stay, odometry, odometry + MOVES_CM[actions])
        return Move(np.full(len(actions), -1), moved, odometry, collided, goal, code, reward, punishment)

    # --- what the robot observes and the env reports --------------------------------------------
    def observe(
        self,
        rows: np.ndarray,
        cells: np.ndarray,
        positions: np.ndarray,
        odometry: np.ndarray,
        keys: np.ndarray,
        steps: np.ndarray,
    ) -> np.ndarray:
        """Observations (a fresh array) of the robots ``rows`` (a bool mask) at ``cells`` (on the lattice) or
        ``positions`` (off it) with ``odometry`` ``(n, 2)`` cm, at counters ``keys``/``steps`` (all ``(n, ...)``)."""
        if self.observation == "cell":
            return cells[rows]  # fancy indexing: a copy
        if not self.robot.on_lattice:
            return self.observe_poses(positions[rows], odometry[rows], keys[rows], steps[rows])
        at = cells[rows]
        return self._observation(self.robot.cell_readings(at, keys[rows], steps[rows]), self.core.cell_odometry[at])

    def observe_poses(
        self, positions: np.ndarray, odometry: np.ndarray, keys: np.ndarray, steps: np.ndarray
    ) -> np.ndarray:
        """Sensor observations ``(n, ...)`` of robots off the lattice's cells (readings at the true ``positions``)."""
        return self._observation(self.robot.pose_readings(positions, keys, steps), self.core.odometry(odometry))

    def _observation(self, readings: np.ndarray, odometry: np.ndarray) -> np.ndarray:
        """Fresh readings ``(n, 32)``, followed by the normalised ``odometry`` ``(n, 2)`` unless not observed."""
        if not self.observe_odometry:
            return readings  # fancy indexing or computed: a fresh array
        return np.concatenate([readings, odometry], axis=1)

    def observe_one(self, cell: int, key: int, step: int) -> np.ndarray | int:
        """:meth:`observe` of one robot on the lattice, in Python values (a single env's step is mostly call
        overhead)."""
        if self.observation == "cell":
            return cell
        readings = self.robot.cell_reading(cell, key, step)
        if not self.observe_odometry:
            return readings.copy()
        return np.concatenate([readings, self.core.cell_odometry[cell]])

    def info(self, punishment: Any, collided: Any, route: Any, position: Any, goal: Any) -> dict[str, Any]:
        """A step's ``info`` (:data:`INFO_KEYS`) of one robot (Python values) or N (arrays); ``route`` is the
        label of the route code (:data:`~twodrl_envs.nomad.core.ROUTE_LABELS`), left out on a map without routes."""
        info = {
            "punishment": punishment,
            "collision": collided,
            "route": route,
            "position_cm": position,
            "is_success": goal,
        }
        if not self.has_routes:
            del info["route"]
        return info

    def frame(self, position: np.ndarray, trajectory: list[tuple[float, float]]) -> np.ndarray:
        """Top-down RGB frame of a robot at ``position`` after ``trajectory``: walls, start, goal, sonar cones."""
        if self._renderer is None:
            from twodrl_envs.nomad.render import OfficeRenderer

            self._renderer = OfficeRenderer(self.core.office)
        return self._renderer.frame(position, trajectory)
