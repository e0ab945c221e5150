"""A survey drive logged as a ROS 2 bag: a robot driven through every reachable lattice cell of a map, ``k`` readings
at each (``sb3-twodrl-survey``; extra ``sb3-twodrl[ros]``, and ``sb3-twodrl[mujoco]`` for the MuJoCo robot).

* **the route** (:func:`coverage_route`): from the map's start, 10 cm moves N/E/S/W to the nearest unvisited
  neighbour (straight on first, then N, E, S, W: a back-and-forth sweep where the room allows), and from a dead end
  along a shortest lattice path to the nearest unvisited cell; every cell reachable from the start, none twice
  more than the sweep needs;
* **the drive** (:func:`drive_survey`): the robot (through the :class:`~twodrl_envs.nomad.core.Robot` seam: the
  MuJoCo robot of ``NomadOfficeMuJoCo-v0`` or the artifact model of ``NomadOfficeReal-v0``) commands the route's
  10 cm moves, closed loop on its localised pose as a robot with a localiser (AMCL) on the map drives waypoints:
  while the localised pose is not in the route's next cell, it commands the first move of a shortest lattice path
  there. The simulation's localiser is exact: the localised pose is the true pose. The robot stops ``k`` times at
  each cell the first time it is localised there: ``k`` readings at one pose, each drawn as an episode of its own
  (the stand-in robots draw some sensor errors once per episode, such as the MuJoCo robot's turret heading: a
  cell's readings vary as they will over the episodes a policy drives; the drive's motion is one episode). A
  move that touches a wall is a bump (the robot stays where it was, as in the envs) and the next try takes
  another way; a cell of the route not reached after :data:`MAX_TRIES` moves is skipped (counted; a later pass
  may still survey it).
* **the odometry**: the robot's own dead reckoning, drift included (the MuJoCo robot's measured motion misread by
  the model's motion error; the artifact model's commanded moves while its true motion drifts): over a survey it
  drifts far more than over an episode, which is why the bag also holds the localised pose and the import files
  readings by it;
* **the bag** (:func:`write_survey_bag`): what ``ros2 bag record`` holds on such a robot, SQLite3 or MCAP: per
  sensor a ``sensor_msgs/msg/Range`` (or per ring a ``LaserScan``) in metres with ``min_range``/``max_range``,
  ``radiation_type`` (ULTRASOUND sonar, INFRARED IR) and the sensor's frame id, ``+inf`` beyond the maximum
  (REP 117); ``/odom`` (``nav_msgs/msg/Odometry``, frame ``odom``: x forward = north from the start, REP 103),
  ``/amcl_pose`` (``geometry_msgs/msg/PoseWithCovarianceStamped``, frame ``map``: x east, y north) and
  ``/ground_truth`` (``Odometry``, frame ``map``), each after every move and before every reading. The bag's
  clock is the drive's: :data:`MOVE_S` per move, :data:`READING_S` per reading.

``sb3-twodrl-record-database --from-bag BAG --pose-topic /amcl_pose --pose-frame map`` imports it to the
database recorded directly at the same poses (:func:`survey_database`).
"""

from __future__ import annotations

import argparse
import csv
import time
from collections import deque
from collections.abc import Callable, Collection
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.analysis.bags import (
    GROUND_TRUTH_TOPIC,
    IR_SCAN_TOPIC,
    IR_TOPIC,
    MAP_FRAME,
    ODOMETRY,
    ODOMETRY_TOPIC,
    RANGE,
    SONAR_SCAN_TOPIC,
    SONAR_TOPIC,
    STORAGES,
    _from_map,
    header,
    import_rosbags,
    odometry_message,
    range_message,
    scan_message,
    sensor_rings,
)
from twodrl_envs.memorable.database import SensorDatabase, import_readings
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import OfficeCore, Robot, continuous_move, episode_key, episode_keys, office_core
from twodrl_envs.nomad.geometry import MOVES_CM, SHIPPED_MAPS, STEP_CM, Lattice
from twodrl_envs.nomad.physics import MuJoCoRobot
from twodrl_envs.nomad.realistic import RealisticModel, RealisticRobot

ROBOTS = ("mujoco", "artifact")
"""``mujoco``: ``NomadOfficeMuJoCo-v0``'s MuJoCo robot; ``artifact``: ``NomadOfficeReal-v0``'s artifact model."""
MOVE_S = 0.5
"""The bag's clock per move: 10 cm at 25 cm/s (the MuJoCo robot's commanded speed) and the stop."""
READING_S = 0.25
"""The bag's clock per reading (the 16 sonars and 16 IR sensors each once)."""
MAX_TRIES = 50
"""Moves the drive spends on one cell of the route before it skips it."""
LOCALISED_TOPIC = "/amcl_pose"
"""The localised pose (``geometry_msgs/msg/PoseWithCovarianceStamped`` in the map's frame), as AMCL publishes it."""
LOCALISED = "geometry_msgs/msg/PoseWithCovarianceStamped"
_NORTH = (0.0, 0.0, float(np.sin(np.pi / 4)), float(np.cos(np.pi / 4)))  # facing north in the map's frame: yaw 90 deg
_ORDER = (0, 1, 2, 3)  # N, E, S, W: the tie order after going straight on


def _neighbours(lattice: Lattice, cell: int, first: int) -> list[tuple[int, int]]:
    """``(action, next cell)`` of the free moves from ``cell``, action ``first`` (straight on) first."""
    order = (first, *(a for a in _ORDER if a != first)) if first >= 0 else _ORDER
    return [(a, int(lattice.moves[cell, a])) for a in order if lattice.moves[cell, a] >= 0]


def _path(lattice: Lattice, source: int, done: Callable[[int], bool], banned: Collection[int] = ()) -> list[int]:
    """Actions of a shortest lattice path from ``source`` to the nearest cell where ``done`` holds (``[]``: ``source``
    itself; ``LookupError``: none reachable); ``banned`` actions are not taken from ``source``."""
    if done(source):
        return []
    parent = {source: (-1, -1)}
    queue = deque([source])
    while queue:
        cell = queue.popleft()
        for action, nxt in _neighbours(lattice, cell, -1):
            if nxt in parent or (cell == source and action in banned):
                continue
            parent[nxt] = (cell, action)
            if done(nxt):
                actions = []
                while nxt != source:
                    nxt, action = parent[nxt]
                    actions.append(action)
                return actions[::-1]
            queue.append(nxt)
    raise LookupError(f"no lattice path from cell {source}")


def coverage_route(core: OfficeCore) -> np.ndarray:
    """Lattice cells ``(m + 1,)`` of a route of 10 cm moves from the map's start through every cell reachable from
    it (module docstring); consecutive cells are neighbours on the lattice."""
    lattice = core.lattice
    todo = lattice.reachable.copy()
    cell, heading = core.start_cell, -1
    todo[cell] = False
    left = int(todo.sum())
    route = [cell]
    while left:
        step = next(((a, n) for a, n in _neighbours(lattice, cell, heading) if todo[n]), None)
        actions = [step[0]] if step is not None else _path(lattice, cell, lambda c: bool(todo[c]))
        for action in actions:
            cell, heading = int(lattice.moves[cell, action]), action
            route.append(cell)
            if todo[cell]:
                todo[cell] = False
                left -= 1
    return np.array(route, dtype=np.int64)


def _cell_of(lattice: Lattice, xy: np.ndarray) -> int:
    """The free lattice cell nearest to ``xy`` (cm) when its lattice point is free, else -1."""
    ix, iy = np.round((np.asarray(xy) - lattice.origin) / STEP_CM).astype(int)
    if not (0 <= ix < lattice.shape[0] and 0 <= iy < lattice.shape[1]):
        return -1
    return int(lattice.grid[ix, iy])


def cells_of(lattice: Lattice, xy: np.ndarray) -> np.ndarray:
    """:func:`_cell_of` of positions ``(n, 2)`` cm: the cell a reading at each would be filed under (-1: none)."""
    return np.array([_cell_of(lattice, p) for p in np.asarray(xy, dtype=np.float64).reshape(-1, 2)], dtype=np.int64)


def make_robot(robot: str, core: OfficeCore, model: RealisticModel | None = None) -> Robot:
    """The :class:`~twodrl_envs.nomad.core.Robot` named ``robot`` (:data:`ROBOTS`) on ``core``'s map."""
    if robot == "mujoco":
        return MuJoCoRobot(core, model)
    if robot == "artifact":
        return RealisticRobot(core, model)
    raise ValueError(f"robot must be one of {ROBOTS}, got {robot!r}")


@dataclass(frozen=True)
class Survey:
    """A survey drive (:func:`drive_survey`), positions in cm in the map's frame (x east, y north).

    ``poses``: after the start and every move, the bag time ``pose_s`` ``(p,)``, the true pose ``truth_cm``
    ``(p, 2)`` (the localised pose: the simulation's localiser is exact) and the odometry ``odometry_cm``
    ``(p, 2)``; ``readings``: ``ranges_cm`` ``(n, 32)`` as the robot reports them, taken at bag time
    ``reading_s`` ``(n,)`` at pose ``pose_of`` ``(n,)`` (an index into the poses) and filed under ``cell``
    ``(n,)``; ``route`` the planned cells; ``move_count`` the moves commanded, ``bumps`` those that touched a wall,
    ``skipped`` the route cells given up (:data:`MAX_TRIES`).
    """

    map: str
    robot: str
    k: int
    seed: int
    route: np.ndarray
    pose_s: np.ndarray
    truth_cm: np.ndarray
    odometry_cm: np.ndarray
    reading_s: np.ndarray
    pose_of: np.ndarray
    ranges_cm: np.ndarray
    cell: np.ndarray
    move_count: int
    bumps: int
    skipped: int

    @property
    def cells(self) -> int:
        """Cells with readings."""
        return len(np.unique(self.cell))

    def misfiled(self, pose: str = "odometry") -> np.ndarray:
        """Per reading, whether ``pose`` (``"odometry"`` or ``"truth"``) files it under another cell than the
        truth's (a cell -1: off the free lattice)."""
        where = {"odometry": self.odometry_cm, "truth": self.truth_cm}[pose][self.pose_of]
        core = office_core(self.map)
        return cells_of(core.lattice, where) != self.cell

    def odometry_error_cm(self) -> np.ndarray:
        """Per reading, the distance (cm) between the odometry and the true pose."""
        return np.linalg.norm(self.odometry_cm[self.pose_of] - self.truth_cm[self.pose_of], axis=1)


def _check_int(name: str, value: object, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise ValueError(f"{name} must be an int >= {low}, got {value!r}")
    return int(value)


def drive_survey(
    map: str | Path | None = None,
    *,
    robot: str = "mujoco",
    k: int = 8,
    seed: int = 0,
    model: RealisticModel | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Survey:
    """Drive ``robot`` (:data:`ROBOTS`) along :func:`coverage_route` of ``map``, ``k`` readings per cell (module
    docstring); ``model`` is the robot's :class:`~twodrl_envs.nomad.realistic.RealisticModel` (default its env's),
    ``seed`` draws the drive's noise (episode 0 of the seed: the odometry's per-drive scale and misalignment) and the
    readings' (reading ``n``: episode ``n + 1``).
    ``progress(cells done, cells)`` is called after every stop."""
    if robot not in ROBOTS:
        raise ValueError(f"robot must be one of {ROBOTS}, got {robot!r}")
    k, seed = _check_int("k", k, 1), _check_int("seed", seed, 0)
    core = office_core(map)
    bot = make_robot(robot, core, model)
    lattice, office = core.lattice, core.office
    route = coverage_route(core)
    total = int(lattice.reachable.sum())
    key = np.array([episode_key(seed, 0)], dtype=np.uint64)
    truth = np.array(office.start, dtype=np.float64)
    odometry = truth.copy()
    physics = bot if isinstance(bot, MuJoCoRobot) else None  # moves in MuJoCo, from where it is placed
    if physics is not None:
        physics.reset_motion(truth)
    clock, step = 0.0, 0  # step: the drive's move counter
    pose_s, truths, odometries = [clock], [truth.copy()], [odometry.copy()]
    reading_s: list[float] = []
    pose_of: list[int] = []
    ranges: list[np.ndarray] = []
    filed: list[int] = []
    surveyed = np.zeros(len(lattice.cells), dtype=bool)
    move_count = bumps = skipped = 0
    span = sensors.HIGH_CM - sensors.LOW_CM

    def stop(cell: int) -> None:
        nonlocal clock
        first = len(ranges) + 1  # reading n draws as episode n + 1 of the seed (the drive is episode 0)
        keys = episode_keys(np.full(k, seed, dtype=np.uint64), np.arange(first, first + k))
        normalised = bot.pose_readings(np.repeat(truth[None], k, axis=0), keys, np.ones(k, dtype=np.int64))
        for reading in sensors.LOW_CM + normalised.astype(np.float64) * span:
            clock += READING_S
            reading_s.append(clock)
            pose_of.append(len(truths) - 1)
            ranges.append(reading)
            filed.append(cell)
        surveyed[cell] = True
        if progress is not None:
            progress(int(surveyed.sum()), total)

    here = _cell_of(lattice, truth)
    stop(here)
    for goal in route[1:].tolist():
        tries, banned = 0, set[int]()
        while here != goal:
            if tries == MAX_TRIES:
                skipped += 1
                break
            tries += 1
            try:
                action = _path(lattice, here, goal.__eq__, banned)[0]
            except LookupError:  # every way out bumped: try them again (the robot's next moves differ)
                banned.clear()
                continue
            step += 1
            if physics is not None:
                physics.place(truth)
            shift = bot.displacement(np.array([action]), key, np.array([step]))
            target, collided, _, _ = continuous_move(office, truth[None], shift)
            move_count += 1
            clock += MOVE_S
            if collided[0]:
                bumps += 1
                banned.add(action)
            else:
                truth = target[0]
                odometry = odometry + (MOVES_CM[action] if physics is None else physics.odometry_cm)
                banned.clear()
            pose_s.append(clock)
            truths.append(truth.copy())
            odometries.append(odometry.copy())
            located = _cell_of(lattice, truth)
            if located >= 0 and lattice.reachable[located]:
                here = located
                if not surveyed[here]:
                    stop(here)
    return Survey(
        office.source,
        robot,
        k,
        seed,
        route,
        np.array(pose_s),
        np.array(truths),
        np.array(odometries),
        np.array(reading_s),
        np.array(pose_of, dtype=np.int64),
        np.array(ranges).reshape(-1, sensors.N_READINGS),
        np.array(filed, dtype=np.int64),
        move_count,
        bumps,
        skipped,
    )


def survey_database(survey: Survey, *, require_all_cells: bool = True) -> SensorDatabase:
    """The database recorded directly from ``survey``'s readings at the poses they were taken at (no bag): what its
    bag imports to with the localised pose (``--pose-topic /amcl_pose --pose-frame map``)."""
    return import_readings(
        survey.truth_cm[survey.pose_of],
        np.clip(survey.ranges_cm, sensors.LOW_CM, sensors.HIGH_CM),
        map=survey.map,
        source=f"survey of {survey.map}",
        recording={"source": "survey", "robot": survey.robot, "samples_per_cell": survey.k, "seed": survey.seed},
        require_all_cells=require_all_cells,
    )


def _localised_message(typestore: Any, ns: int, xy_cm: np.ndarray) -> Any:
    """A ``PoseWithCovarianceStamped`` at ``xy_cm`` in the map's frame, facing north (the exact localiser: zero
    covariance)."""
    types = typestore.types
    x, y, z, w = _NORTH
    return types[LOCALISED](
        header=header(typestore, ns, MAP_FRAME),
        pose=types["geometry_msgs/msg/PoseWithCovariance"](
            pose=types["geometry_msgs/msg/Pose"](
                position=types["geometry_msgs/msg/Point"](x=float(xy_cm[0] / 100.0), y=float(xy_cm[1] / 100.0), z=0.0),
                orientation=types["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w),
            ),
            covariance=np.zeros(36),
        ),
    )


def write_survey_bag(
    survey: Survey,
    path: str | Path,
    *,
    storage: str = "sqlite3",
    scan: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Write ``survey`` as its robot's ``ros2 bag record`` holds it (module docstring) at ``path`` (a new folder),
    ``storage`` ``"sqlite3"`` or ``"mcap"``; ``scan``: one ``LaserScan`` per ring (``/sonar_scan``, ``/ir_scan``)
    instead of a ``Range`` topic per sensor. ``progress(readings written, readings)`` is called every 1000
    readings."""
    if storage not in STORAGES:
        raise ValueError(f"storage must be one of {STORAGES}, got {storage!r}")
    if not isinstance(scan, bool):
        raise TypeError(f"scan must be a bool, got {type(scan).__name__}: {scan!r}")
    path = Path(path)
    if path.exists():
        raise ValueError(f"bag {path} already exists: a survey writes a new bag")
    rings = sensor_rings(SONAR_SCAN_TOPIC, IR_SCAN_TOPIC) if scan else sensor_rings(SONAR_TOPIC, IR_TOPIC)
    rosbags = import_rosbags()
    typestore = rosbags.typesys.get_typestore(rosbags.typesys.Stores.ROS2_HUMBLE)
    start = office_core(survey.map).office.start
    odometry_m = _from_map(survey.odometry_cm, "start", start)
    north = typestore.types["geometry_msgs/msg/Quaternion"](*_NORTH)
    plugin = rosbags.rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbags.rosbag2.StoragePlugin.SQLITE3
    readings_at = np.searchsorted(survey.pose_of, np.arange(len(survey.pose_s) + 1))
    with rosbags.rosbag2.Writer(path, version=8, storage_plugin=plugin) as writer:
        odom = writer.add_connection(ODOMETRY_TOPIC, ODOMETRY, typestore=typestore)
        localised = writer.add_connection(LOCALISED_TOPIC, LOCALISED, typestore=typestore)
        truth = writer.add_connection(GROUND_TRUTH_TOPIC, ODOMETRY, typestore=typestore)
        sensors_out = [
            (ring, [writer.add_connection(t, ring.msgtype, typestore=typestore) for t in ring.topics]) for ring in rings
        ]

        def poses(ns: int, p: int) -> None:
            writer.write(odom, ns, typestore.serialize_cdr(odometry_message(typestore, ns, odometry_m[p]), ODOMETRY))
            xy = survey.truth_cm[p]
            writer.write(localised, ns, typestore.serialize_cdr(_localised_message(typestore, ns, xy), LOCALISED))
            message = odometry_message(typestore, ns, xy / 100.0, MAP_FRAME)
            message.pose.pose.orientation = north
            writer.write(truth, ns, typestore.serialize_cdr(message, ODOMETRY))

        written = 0
        for p, when in enumerate(survey.pose_s):
            poses(10**9 + round(when * 1e9), p)
            for n in range(readings_at[p], readings_at[p + 1]):
                ns = 10**9 + round(survey.reading_s[n] * 1e9)
                poses(ns, p)
                offset = 0
                for ring, connections in sensors_out:
                    for j, connection in enumerate(connections):
                        offset += 1000
                        column = ring.first + j
                        if ring.msgtype == RANGE:
                            msg = range_message(typestore, ns + offset, float(survey.ranges_cm[n, column]), column)
                        else:
                            msg = scan_message(
                                typestore, ns + offset, survey.ranges_cm[n, column : column + 16], column
                            )
                        writer.write(connection, ns + offset, typestore.serialize_cdr(msg, ring.msgtype))
                written += 1
                if progress is not None and written % 1000 == 0:
                    progress(written, len(survey.ranges_cm))
    return path


def write_waypoints(survey: Survey, path: str | Path) -> Path:
    """The route as waypoints a real robot's navigation stack (or its driver) follows: a CSV file with columns
    ``x_m, y_m, readings``, metres in the map's frame (x east, y north), ``readings`` the readings to take on
    arrival (``k`` at a cell's first visit, else 0)."""
    core = office_core(survey.map)
    path = Path(path)
    first = np.zeros(len(survey.route), dtype=bool)
    first[np.unique(survey.route, return_index=True)[1]] = True
    with path.open("w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["x_m", "y_m", "readings"])
        for cell, stop in zip(survey.route, first, strict=True):
            x, y = core.lattice.cells[cell] / 100.0
            out.writerow([f"{x:.2f}", f"{y:.2f}", survey.k if stop else 0])
    return path


def _size(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) if path.is_dir() else path.stat().st_size


def main(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-survey``: drive a stand-in robot through every reachable cell of a map and write the bag."""
    parser = argparse.ArgumentParser(
        prog="sb3-twodrl-survey",
        description="Drive a robot (the MuJoCo robot or the artifact model) along a coverage route through every "
        "lattice cell reachable from the map's start, K readings per cell, and write the drive as a ROS 2 bag: "
        "a sensor_msgs/Range per sensor (or a LaserScan per ring) in metres, /odom (the robot's odometry, drift "
        "included), /amcl_pose (the localised pose, map frame) and /ground_truth. Import it with "
        "sb3-twodrl-record-database --from-bag BAG --pose-topic /amcl_pose --pose-frame map.",
        epilog="example: sb3-twodrl-survey --map my_office.json --robot mujoco --out survey_bag",
    )
    parser.add_argument(
        "--map",
        default=None,
        help=f"built-in map name ({', '.join(SHIPPED_MAPS)}), map JSON file or generated:SIZE:SEED (default: office)",
    )
    parser.add_argument(
        "--robot",
        choices=ROBOTS,
        default="mujoco",
        help="mujoco: NomadOfficeMuJoCo-v0's physics robot (default); artifact: NomadOfficeReal-v0's artifact model",
    )
    parser.add_argument("--k", type=int, default=8, help="readings per cell (default 8)")
    parser.add_argument("--seed", type=int, default=0, help="the drive's noise seed (default 0)")
    parser.add_argument("--out", type=Path, required=True, help="the bag to write (a new folder)")
    parser.add_argument("--storage", choices=STORAGES, default="sqlite3", help="the bag's storage (default sqlite3)")
    parser.add_argument(
        "--scan", action="store_true", help="a LaserScan per ring (/sonar_scan, /ir_scan) instead of a Range per sensor"
    )
    parser.add_argument(
        "--waypoints-out", type=Path, default=None, help="also write the route as waypoints (CSV: x_m, y_m, readings)"
    )
    args = parser.parse_args(argv)
    if args.k < 1:
        parser.error(f"--k must be >= 1, got {args.k}")
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    if args.out.exists():
        parser.error(f"--out {args.out} already exists: a survey writes a new bag")
    for flag, path in (("--out", args.out), ("--waypoints-out", args.waypoints_out)):
        if path is not None and not path.resolve().parent.is_dir():
            parser.error(f"{flag}: directory {str(path.parent)!r} does not exist")
    try:
        import_rosbags()
    except ModuleNotFoundError as err:
        parser.error(f"--out: {err}")
    began = shown = time.monotonic()

    def report(done: int, total: int, what: str) -> None:
        nonlocal shown
        now = time.monotonic()
        if now - shown >= 5.0 or done == total:
            shown = now
            print(f"sb3-twodrl-survey: {what} {done}/{total} ({now - began:.0f} s)", flush=True)

    try:
        survey = drive_survey(
            args.map, robot=args.robot, k=args.k, seed=args.seed, progress=lambda d, t: report(d, t, "cells")
        )
    except ValueError as err:  # a bad map: the map loader's one-line message
        parser.error(f"--map: {err}")
    except ModuleNotFoundError as err:  # the MuJoCo robot without mujoco
        parser.error(f"--robot {args.robot}: {err}")
    driven = time.monotonic()
    write_survey_bag(
        survey, args.out, storage=args.storage, scan=args.scan, progress=lambda d, t: report(d, t, "readings written")
    )
    if args.waypoints_out is not None:
        write_waypoints(survey, args.waypoints_out)
        print(f"sb3-twodrl-survey: wrote the route's {len(survey.route)} waypoints to {args.waypoints_out}")
    total = int(office_core(survey.map).lattice.reachable.sum())
    odometry = survey.odometry_error_cm()
    print(
        f"sb3-twodrl-survey: /odom drifted {np.median(odometry):.0f} cm (median; at most {odometry.max():.0f}) from "
        f"the true pose and would file {survey.misfiled().mean():.0%} of the readings under another cell: import "
        f"with --pose-topic {LOCALISED_TOPIC} --pose-frame map"
    )
    print(
        f"sb3-twodrl-survey: {survey.cells} of {total} cells, {len(survey.ranges_cm)} readings ({survey.k} per cell), "
        f"{survey.move_count} moves ({survey.bumps} bumps, {survey.skipped} waypoints skipped), "
        f"{survey.pose_s[-1] / 60:.0f} min of robot time; {time.monotonic() - began:.0f} s (drive "
        f"{driven - began:.0f} s); wrote {args.out} ({_size(args.out) / 1e6:.1f} MB, {args.storage})"
    )
