"""The office's rules, written once for one robot or N: the map's tables, moves, eq. 11-12, the robot seam.

* :class:`OfficeCore`: what a map fixes (lattice, exact readings, route and goal labels), built once per map.
* :func:`evaluations`: eq. 11-12, ``r_R = 5`` on the goal, ``r_P = 1`` on a collision (replacing the move
  cost) and ``0.01`` for every other move; the env's reward is ``r_R - r_P``.
* :class:`LatticeOutcomes`: every (cell, action) outcome on the lattice (next cell, collision, goal, route
  code, evaluations), computed from the move table by the rules above; the single env reads it with Python
  indices, the batched env with arrays.
* :func:`continuous_move`: a move off the lattice (swept-disc collision test, bounds, route code, goal).
* :data:`ROUTE_LABELS` / :data:`ROUTE_CODES`: the label of each route code and the code of each label,
  :func:`route_code_at` and :func:`remembered_route` (``info["route"]`` is the route region entered last).
* :class:`Robot`: the one seam between the ideal, realistic and replay (MEMORABLE) robots: how a command
  moves the robot and what it reads. :class:`IdealRobot` is the simulator's.

The envs (``office.NomadOfficeEnv``, ``batched.BatchedNomadOffice`` and their realistic and replay
variants) hold episode state and the Gymnasium API; :mod:`twodrl_envs.nomad.episode` applies these rules to
their episodes, once for both.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path

import numpy as np

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.geometry import (
    MOVES_CM,
    ROBOT_RADIUS_CM,
    ROUTE_REGIONS,
    STEP_CM,
    Lattice,
    OfficeMap,
    build_lattice,
    check_goal_reachable,
    is_generated,
    reachable_from,
    swept_clearance,
)
from twodrl_envs.nomad.maps import load_map, map_source
from twodrl_envs.nomad.sensors import NoiseModel

GOAL_REWARD = 5.0  # r_R, eq. 11
COLLISION_PUNISHMENT = 1.0  # r_P on collision, eq. 12
MOVE_PUNISHMENT = 0.01  # r_P for every (non-colliding) move, eq. 12
ROUTE_LABELS: tuple[str | None, ...] = (None, *ROUTE_REGIONS)
"""``info["route"]`` of route code 0, 1, 2: none yet, then the map's route regions (``shortcut``, ``detour``)."""
ROUTE_CODES = {name: code for code, name in enumerate(ROUTE_LABELS) if name is not None}
"""Route code of each route label."""
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MASK64 = (1 << 64) - 1
_START_SALT = 0x5851F42D4C957F2D
STARTS = ("map", "uniform")
"""Where episodes start: the map's start, or a cell drawn from :attr:`Robot.start_cells` (exploring starts)."""


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

    @cached_property
    def cell_odometry(self) -> np.ndarray:
        """:meth:`odometry` of every lattice cell ``(n_cells, 2)``: on the lattice, odometry is the cell's."""
        return self.odometry(self.lattice.cells)


def route_code_at(office: OfficeMap, xy: np.ndarray) -> np.ndarray:
    """Route code (:data:`ROUTE_CODES`, 0 none) of centre positions ``(..., 2)``; the first route region wins."""
    code = np.zeros(np.shape(xy)[:-1], dtype=np.int64)
    for name, value in reversed(ROUTE_CODES.items()):
        code = np.where(office.in_region(name, xy), value, code)
    return code


def remembered_route(route: np.ndarray, code: np.ndarray) -> np.ndarray:
    """Route codes after moves into cells of route ``code``: the code of a route region entered, else ``route``
    (the one before). ``info["route"]`` is the label of the route region the robot's centre entered last."""
    return np.where(code > 0, code, route)


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

    Every env loads its map here: the file is validated (:func:`~twodrl_envs.nomad.maps.load_map`) and
    its goal must be reachable from the start on the lattice
    (:func:`~twodrl_envs.nomad.geometry.check_goal_reachable`), else ``ValueError``.
    """
    source = map_source(map_path)
    # A generated office never changes; a missing file gets its error from load_map, uncached
    version = -1 if is_generated(source) or not Path(source).exists() else Path(source).stat().st_mtime_ns
    return _core(source, version)


# --- evaluations (eq. 11-12) ----------------------------------------------------------------


def evaluations(collided: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rewards ``r_R - r_P`` and punishments ``r_P`` of moves (eq. 11-12): a collision never reaches the goal."""
    punishment = np.where(collided, COLLISION_PUNISHMENT, MOVE_PUNISHMENT)
    return np.where(goal & ~collided, GOAL_REWARD, 0.0) - punishment, punishment


@dataclass(frozen=True)
class LatticeOutcomes:
    """The outcome of every action from every cell of a move table ``(n_cells, 4)`` (next cell or -1).

    Arrays ``(n_cells, 4)``: ``next_cell`` (the cell itself where the move collides: a collision leaves
    the robot where it was), ``collided``, ``goal``, ``code`` (route code of the next cell, 0 on a
    collision), ``reward`` and ``punishment`` (:func:`evaluations`, plus the progress signal when
    ``progress`` > 0). :attr:`rows` gives them as Python values, for a single env whose step would otherwise be
    numpy call overhead.

    The progress signal (a distance-based training signal for large offices: Mataric 1994's progress estimator,
    Ng, Harada & Russell 1999's shaping) adds ``progress`` to ``r_R`` for a move that brings the robot one move
    closer to the goal (lattice distance ``distance``) and ``progress`` to ``r_P`` for one that takes it a move
    farther: both streams stay >= 0, a reward for progress and a punishment for regress. Undiscounted, it sums to
    ``progress`` times the distance covered, whatever the path (potential-based with potential
    ``-progress * distance``).
    """

    next_cell: np.ndarray
    collided: np.ndarray
    goal: np.ndarray
    code: np.ndarray
    reward: np.ndarray
    punishment: np.ndarray

    @classmethod
    def of(
        cls, core: OfficeCore, moves: np.ndarray, distance: np.ndarray | None = None, progress: float = 0.0
    ) -> LatticeOutcomes:
        """The outcomes of ``moves`` (the lattice's, or a replay's recorded free space) on ``core``'s labels;
        with ``progress`` > 0, the progress signal along ``distance`` (moves to the goal, ``(n_cells,)``)."""
        collided = moves < 0
        next_cell = np.where(collided, np.arange(len(moves))[:, None], moves)
        goal = core.goal[next_cell] & ~collided
        code = np.where(collided, 0, core.route_code[next_cell]).astype(np.int8)
        reward, punishment = evaluations(collided, goal)
        if progress > 0.0:
            if distance is None:
                raise ValueError("the progress signal needs the lattice distance to the goal (distance)")
            with np.errstate(invalid="ignore"):
                gain = distance[:, None] - distance[next_cell]  # +1 closer, -1 farther, 0 on a collision
            gain = np.where(np.isfinite(gain), gain, 0.0)
            reward = reward + progress * gain
            punishment = punishment + progress * np.maximum(-gain, 0.0)
        return cls(next_cell, collided, goal, code, reward, punishment)

    @cached_property
    def rows(self) -> list[list[tuple[int, bool, bool, int, float, float]]]:
        """``rows[cell][action]``: ``(next_cell, collided, goal, code, reward, punishment)`` as Python values."""
        columns = (self.next_cell, self.collided, self.goal, self.code, self.reward, self.punishment)
        lists = [column.tolist() for column in columns]
        return [[tuple(entry) for entry in zip(*cells, strict=True)] for cells in zip(*lists, strict=True)]


def continuous_move(
    office: OfficeMap, positions: np.ndarray, displacement: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Targets ``(n, 2)``, ``collided``, route ``code`` and ``goal`` ``(n,)`` of moves off the lattice.

    A move collides when the robot's disc, swept from ``positions`` to the target, touches a wall, or
    when the target leaves the map's bounds; a colliding robot stays where it was (code 0, no goal).
    """
    target = positions + displacement
    clear = swept_clearance(positions, target, office.walls) > ROBOT_RADIUS_CM
    collided = ~(clear & office.inside_bounds(target))
    code = np.where(collided, 0, route_code_at(office, target))
    goal = office.in_region("goal", target) & ~collided
    return target, collided, code, goal


def goal_distances(core: OfficeCore, moves: np.ndarray, passable: np.ndarray | None = None) -> np.ndarray:
    """Fewest moves ``(n_cells,)`` from each cell to a goal cell by the move table ``moves`` (``inf``: none).

    ``passable`` (bool ``(n_cells,)``) closes the cells where it is False (they get ``inf``).
    """
    open_ = np.ones(len(moves), dtype=bool) if passable is None else passable
    dist = np.where(core.goal & open_, 0.0, np.inf)
    while True:
        nxt = np.where(moves >= 0, dist[np.maximum(moves, 0)], np.inf).min(axis=1) + 1.0
        new = np.where(core.goal | ~open_, dist, np.minimum(dist, nxt))
        if np.array_equal(new, dist):
            return dist
        dist = new


# --- counter-based keys ---------------------------------------------------------------------


def episode_keys(base: np.ndarray, episode: np.ndarray) -> np.ndarray:
    """Noise key of each episode, derived from a seeded base key and the episode counter."""
    return sensors.counter_hash(base + episode.astype(np.uint64) * _GOLDEN, np.zeros(len(base), dtype=np.int64))[
        :, 0
    ].copy()


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


def start_draws(keys: np.ndarray, n: int) -> np.ndarray:
    """Indices ``(len(keys),)`` in ``range(n)`` drawn counter-based from episode keys (exploring starts)."""
    return (sensors.counter_hash(keys ^ np.uint64(_START_SALT), np.zeros(len(keys), dtype=np.int64))[:, 0] % n).astype(
        np.intp
    )


def start_draw(key: int, n: int) -> int:
    """:func:`start_draws` of one episode key, in Python integers."""
    return counter_word(key ^ _START_SALT, 0) % n


def check_starts(starts: object) -> str:
    """``starts`` if it is one of :data:`STARTS`, else ``ValueError``."""
    if not isinstance(starts, str) or starts not in STARTS:
        raise ValueError(f"starts must be one of {STARTS}, got {starts!r}")
    return starts


# --- the robot seam -------------------------------------------------------------------------


class Robot:
    """How a commanded move displaces a robot and what its sensors read: the seam between robots.

    On the lattice (``on_lattice``) a robot moves by the table ``moves`` (next cell or -1 for a
    collision) and reads :meth:`cell_readings`; off it, it moves by :meth:`displacement` and reads
    :meth:`pose_readings`. Per-step randomness comes from ``(episode key, step)`` counters or, for the
    ideal robot's move noise, from each env's own generator (which only :class:`IdealRobot` takes), so N robots
    stepped in one call equal N single ones.
    """

    on_lattice: bool = True
    varying_readings: bool = True
    """Whether a cell's readings vary from visit to visit (noise, recordings): learning them takes more samples."""

    def __init__(self, core: OfficeCore) -> None:
        self.core = core
        self.moves = core.lattice.moves

    def outcomes(self, progress: float = 0.0) -> LatticeOutcomes:
        """:class:`LatticeOutcomes` of :attr:`moves`, with the progress signal of weight ``progress``."""
        if not self.on_lattice:
            raise ValueError(f"{type(self).__name__} moves off the lattice: it has no lattice outcomes")
        return LatticeOutcomes.of(self.core, self.moves, self.goal_distance if progress else None, progress)

    @cached_property
    def goal_distance(self) -> np.ndarray:
        """Fewest moves ``(n_cells,)`` from each cell to the goal by :attr:`moves` (``inf``: none)."""
        return goal_distances(self.core, self.moves)

    @cached_property
    def start_cells(self) -> np.ndarray:
        """Cells an exploring start may draw: reachable from the map's start by :attr:`moves`, outside the goal,
        with a way to the goal (ascending indices)."""
        reached = reachable_from(self.moves, self.core.start_cell)
        return np.flatnonzero(reached & ~self.core.goal & np.isfinite(self.goal_distance))

    def cell_readings(self, cells: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Normalised readings ``(n, 32)`` at lattice cells."""
        raise NotImplementedError(f"{type(self).__name__} does not move on the lattice")

    def cell_reading(self, cell: int, key: int, step: int) -> np.ndarray:
        """:meth:`cell_readings` of one robot ``(32,)`` (a subclass may compute it in Python values)."""
        return self.cell_readings(np.array([cell]), np.array([key], dtype=np.uint64), np.array([step]))[0]

    def pose_readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Normalised readings ``(n, 32)`` at continuous poses ``(n, 2)``."""
        raise NotImplementedError(f"{type(self).__name__} moves only on the lattice")

    def displacement(self, actions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """True displacements ``(n, 2)`` in cm of the commanded 10 cm moves ``actions`` ``(n,)`` at counters
        ``keys``/``steps``."""
        raise NotImplementedError(f"{type(self).__name__} moves only on the lattice")

    def check_start(self, xy: np.ndarray, cell: int) -> None:
        """Raise ``ValueError`` if this robot cannot start at ``xy`` (lattice ``cell``, -1 off it)."""


class IdealRobot(Robot):
    """The simulator's robot (``NomadOffice-v0``): exact readings plus optional per-step ``noise``; exact
    10 cm moves unless ``step_sd_cm`` / ``slip_sd_cm`` perturb each move's length and lateral position,
    which takes the robot off the lattice (readings ray cast at the true pose).

    Its move noise draws from each env's own generator: ``generators()`` gives them, one per robot of a
    :meth:`displacement` call (a single env's ``np_random``; a batched env's, seeded as single ones), and
    a robot with move noise needs it.
    """

    def __init__(
        self,
        core: OfficeCore,
        noise: NoiseModel | None = None,
        step_sd_cm: float = 0.0,
        slip_sd_cm: float = 0.0,
        generators: Callable[[], Sequence[np.random.Generator]] | None = None,
    ) -> None:
        super().__init__(core)
        self.noise = noise
        self.step_sd_cm = step_sd_cm
        self.slip_sd_cm = slip_sd_cm
        self.on_lattice = step_sd_cm == 0.0 and slip_sd_cm == 0.0
        self.varying_readings = noise is not None
        if not self.on_lattice and generators is None:
            raise ValueError("an IdealRobot with step_sd_cm or slip_sd_cm needs its envs' generators (generators)")
        self.generators = generators

    @cached_property
    def _sd_table(self) -> np.ndarray:
        assert self.noise is not None
        return self.noise.sd(self.core.ranges)

    def cell_readings(self, cells: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        if self.noise is None:
            return self.core.readings[cells]
        return sensors.normalise(self.noise.apply(self.core.ranges[cells], keys, steps, self._sd_table[cells]))

    def cell_reading(self, cell: int, key: int, step: int) -> np.ndarray:
        if self.noise is None:
            return self.core.readings[cell]
        return super().cell_reading(cell, key, step)

    def pose_readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        ranges = sensors.exact_ranges(self.core.office, positions)
        if self.noise is not None:
            ranges = self.noise.apply(ranges, keys, steps)
        return sensors.normalise(ranges)

    def displacement(self, actions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """The command plus ``step_sd_cm`` along and ``slip_sd_cm`` across, drawn from each env's generator (the
        counters are unused: the draws follow each generator's order, as a single env's ``np_random``)."""
        assert self.generators is not None
        rngs = self.generators()
        command = MOVES_CM[actions]
        along = [rng.normal(0.0, self.step_sd_cm) if self.step_sd_cm else 0.0 for rng in rngs]
        lateral = [rng.normal(0.0, self.slip_sd_cm) if self.slip_sd_cm else 0.0 for rng in rngs]
        unit = command / STEP_CM
        normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1)
        return command + np.array(along)[:, None] * unit + np.array(lateral)[:, None] * normal
