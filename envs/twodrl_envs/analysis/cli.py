"""sb3-twodrl-record-database: check a map and record its MEMORABLE sensor database.

A virtual robot visits every cell of the office reachable from the start. --model realistic (default): the
stand-in robot of NomadOfficeReal-v0 drives to each cell by dead reckoning, K times, and files each reading
(16 sonar, 16 IR) under its odometry's cell, as a real robot would. --model noise: placed exactly on each cell,
K noisy ideal readings; --model ideal: exact. A user with a real robot imports their log instead: a CSV file
(--from-csv log.csv) or a ROS 2 bag (--from-bag BAG, needs pip install "sb3-twodrl[ros]"; its topics named by
--sonar-topic, --ir-topic, --odom-topic, --pose-topic; each message checked: units, ranges, scan order, frame ids
against --sonar-frame, --ir-frame; see docs/bags.md). An import prints its coverage (--coverage-png draws it).
--check only loads and checks the map and prints what
the robot sees of it.

    sb3-twodrl-record-database --map my_office.json --check
    sb3-twodrl-record-database --map my_office.json --out my_office_k8.npz
    sb3-twodrl-record-database --map my_office.json --from-csv robot_log.csv --out my_robot.npz
    sb3-twodrl-record-database --map my_office.json --from-bag robot_bag --out my_robot.npz --coverage-png cover.png
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.analysis.bags import (
    IR_FRAME,
    IR_RING_FRAME,
    IR_TOPIC,
    ODOMETRY_TOPIC,
    POSE_FRAMES,
    SONAR_FRAME,
    SONAR_RING_FRAME,
    SONAR_TOPIC,
    import_bag,
)
from twodrl_envs.analysis.coverage import PLOTS_HINT, coverage, plot_coverage
from twodrl_envs.analysis.dilemma import distance_to_goal
from twodrl_envs.memorable.database import SensorDatabase, import_csv, load_database, save_database
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad.core import ROUTE_CODES, OfficeCore, office_core
from twodrl_envs.nomad.geometry import SHIPPED_MAPS, OfficeMap
from twodrl_envs.nomad.maps import map_data
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import NoiseModel

MODELS = ("realistic", "noise", "ideal")


def _rect(office: OfficeMap, name: str) -> str:
    return "[" + ", ".join(f"{v:g}" for v in office.regions[name]) + "]"


def in_obstacles(core: OfficeCore) -> np.ndarray:
    """Which lattice cells ``(n_cells,)`` lie inside one of the map's obstacle polygons (even-odd rule).

    The lattice keeps every point whose disc clears the walls, so the middle of an obstacle wider than the robot
    is a lattice cell; no move reaches it.
    """
    xy = core.lattice.cells
    inside = np.zeros(len(xy), dtype=bool)
    for polygon in map_data(core.office.source).get("obstacles", []):
        vertices = np.asarray(polygon, dtype=np.float64)
        crossings = np.zeros(len(xy), dtype=bool)
        for (ax, ay), (bx, by) in zip(vertices, np.roll(vertices, -1, axis=0), strict=True):
            straddles = (ay > xy[:, 1]) != (by > xy[:, 1])
            with np.errstate(divide="ignore", invalid="ignore"):
                x_cross = ax + (xy[:, 1] - ay) * (bx - ax) / (by - ay)
            crossings ^= straddles & (xy[:, 0] < x_cross)
        inside |= crossings
    return inside


def describe_map(core: OfficeCore) -> str:
    """A few lines on a checked map: size, start, lattice cells, goal, shortest path, route regions.

    Lattice points inside obstacles are not counted as free cells (they are reported apart); the free cells that
    the start cannot reach are walled off from it.
    """
    office, lattice = core.office, core.lattice
    x0, y0, x1, y1 = office.bounds
    moves = distance_to_goal(core)[core.start_cell]
    inside = in_obstacles(core)
    free = int((~inside).sum())
    reachable = int((lattice.reachable & ~inside).sum())
    counts = f"  {free} free lattice cells, {reachable} reachable from the start"
    if free > reachable:
        counts += f" ({free - reachable} walled off from it)"
    if inside.any():
        counts += f"; {int(inside.sum())} more lattice points lie inside obstacles"
    lines = [
        f"map {office.name!r} ({office.source}): OK",
        f"  {x1 - x0:g} x {y1 - y0:g} cm, start ({office.start[0]:g}, {office.start[1]:g}), "
        f"{len(office.walls)} wall segments",
        counts,
        f"  goal {_rect(office, 'goal')}: {int((core.goal & lattice.reachable).sum())} reachable cells, "
        f"shortest path {moves:.0f} moves",
    ]
    if office.has_routes:
        for name, code in ROUTE_CODES.items():
            cells = int(((core.route_code == code) & lattice.reachable).sum())
            lines.append(f"  {name} region {_rect(office, name)}: {cells} reachable cells")
    else:
        lines.append("  no route regions: info has no 'route', no route metrics")
    return "\n".join(lines)


def _import(args: argparse.Namespace) -> SensorDatabase:
    """The database of the command's CSV or bag import, complete or not (the command reports missing cells)."""
    if args.from_csv is not None:
        return import_csv(args.from_csv, map=args.map, require_all_cells=False, per_cell=args.k)
    return import_bag(args.from_bag, map=args.map, per_cell=args.k, require_all_cells=False, **bag_options(args))


def add_bag_arguments(parser: argparse.ArgumentParser, note: str = "") -> None:
    """The options that name a bag's topics and frames (``--sonar-topic`` ... ``--pose-frame``), as
    ``sb3-twodrl-record-database --from-bag`` and ``sb3-twodrl-replay-bag`` take them; ``note`` opens each help."""
    parser.add_argument(
        "--sonar-topic",
        default=SONAR_TOPIC,
        help=f"{note}sonar topics, a pattern with {{i}} (16 sensor_msgs/msg/Range topics) or one LaserScan topic "
        f"(default {SONAR_TOPIC})",
    )
    parser.add_argument(
        "--ir-topic", default=IR_TOPIC, help=f"{note}infrared topics, as --sonar-topic (default {IR_TOPIC})"
    )
    parser.add_argument(
        "--odom-topic",
        default=ODOMETRY_TOPIC,
        help=f"{note}the nav_msgs/msg/Odometry topic (default {ODOMETRY_TOPIC})",
    )
    parser.add_argument(
        "--pose-topic",
        default=None,
        help=f"{note}where the readings were taken: an Odometry, PoseStamped or PoseWithCovarianceStamped topic, "
        "read instead of --odom-topic (which the bag then need not hold; default: --odom-topic)",
    )
    parser.add_argument(
        "--sonar-frame",
        default=None,
        help=f"{note}the sonar messages' frame ids, a pattern with {{i}} for Range topics (default {SONAR_FRAME}, "
        f"or {SONAR_RING_FRAME} for a LaserScan)",
    )
    parser.add_argument(
        "--ir-frame",
        default=None,
        help=f"{note}the infrared messages' frame ids, as --sonar-frame (default {IR_FRAME}, or {IR_RING_FRAME})",
    )
    parser.add_argument(
        "--pose-frame",
        choices=POSE_FRAMES,
        default="start",
        help=f"{note}start: the pose is odometry of a robot switched on at the map's start facing north (x "
        "forward, y left); map: the pose is in the map's frame, x east, y north (default start)",
    )


def bag_options(args: argparse.Namespace) -> dict[str, Any]:
    """The bag reader's keyword arguments (:func:`~twodrl_envs.analysis.bags.read_bag`) from
    :func:`add_bag_arguments`' options."""
    return {
        "sonar": args.sonar_topic,
        "ir": args.ir_topic,
        "odometry": args.odom_topic,
        "pose": args.pose_topic,
        "pose_frame": args.pose_frame,
        "sonar_frame": args.sonar_frame,
        "ir_frame": args.ir_frame,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="sb3-twodrl-record-database", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--map",
        default=None,
        help=f"built-in map name ({', '.join(SHIPPED_MAPS)}), map JSON file or generated:SIZE:SEED (default: office)",
    )
    parser.add_argument("--check", action="store_true", help="check the map and describe it; record nothing")
    parser.add_argument("--out", type=Path, default=None, help="output .npz (required unless --check)")
    parser.add_argument(
        "--k",
        type=int,
        default=None,
        help="readings per cell: recorded (default 8); imported: keep each cell's first K (default all)",
    )
    parser.add_argument("--seed", type=int, default=0, help="noise seed of the recording (default 0)")
    parser.add_argument(
        "--model",
        choices=MODELS,
        default="realistic",
        help="realistic: the stand-in robot driving by dead reckoning (default); noise: noisy ideal; ideal: exact",
    )
    parser.add_argument("--from-csv", type=Path, default=None, help="import a CSV log instead of recording")
    parser.add_argument("--from-bag", type=Path, default=None, help="import a ROS 2 bag (folder or file) instead")
    add_bag_arguments(parser, "bag: ")
    parser.add_argument("--allow-missing", action="store_true", help="imports: allow reachable cells without readings")
    parser.add_argument(
        "--coverage-png",
        type=Path,
        default=None,
        help="imports: draw the cells with readings to this PNG (needs matplotlib: the plots extra)",
    )
    args = parser.parse_args(argv)
    if not args.check:
        if args.out is None:
            parser.error("--out is required (the .npz file to write), unless --check")
        if args.out.suffix != ".npz":
            parser.error(f"--out must end in .npz, got {str(args.out)!r}")
        if not args.out.parent.is_dir():
            parser.error(f"--out: directory {str(args.out.parent)!r} does not exist")
        if args.k is not None and args.k < 1:
            parser.error(f"--k must be >= 1, got {args.k}")
        if args.from_csv is not None and args.from_bag is not None:
            parser.error("pass --from-csv or --from-bag, not both")
        if args.coverage_png is not None:
            if args.from_csv is None and args.from_bag is None:
                parser.error("--coverage-png draws an import's coverage: pass --from-csv or --from-bag")
            if args.coverage_png.suffix != ".png" or not args.coverage_png.parent.is_dir():
                parser.error(f"--coverage-png must be a .png in an existing directory, got {str(args.coverage_png)!r}")
            if importlib.util.find_spec("matplotlib") is None:
                parser.error(f"--coverage-png: {PLOTS_HINT}")
    try:
        core = office_core(args.map)
    except (ValueError, TypeError) as err:
        parser.error(f"--map: {err}")
    print(describe_map(core))
    if args.check:
        return
    k = 8 if args.k is None else args.k
    if args.from_csv is not None or args.from_bag is not None:
        flag = "--from-csv" if args.from_csv is not None else "--from-bag"
        log = args.from_csv or args.from_bag
        try:  # one line: what is wrong with the log, or what to install
            db = _import(args)
            report = coverage(db, core)
            print(report.describe())
            picture = "" if args.coverage_png is None else f" (drawn: {plot_coverage(db, core, args.coverage_png)})"
            if len(report.missing_cm) and not args.allow_missing:
                raise ValueError(
                    f"{log}: {len(report.missing_cm)} of {report.reachable} reachable cells have no readings "
                    f"(e.g. {report.missing_examples()}){picture}; drive there and import again, or pass "
                    "--allow-missing (cells without readings then count as obstacles)"
                )
            db.check_map(core, source=str(log))
        except (ValueError, ModuleNotFoundError) as err:
            parser.exit(2, f"{parser.prog}: error: {flag}: {err}\n")
    elif args.model == "realistic":
        db = record_database(k, map=args.map, model=RealisticModel(), seed=args.seed, progress=True)
    else:
        noise = NoiseModel() if args.model == "noise" else None
        db = record_database(k, map=args.map, noise=noise, seed=args.seed, progress=True)
    path = save_database(db, args.out)
    load_database(path, core)  # read back strictly
    recorded = int((db.counts > 0).sum())
    print(
        f"wrote {path}: {recorded} cells, {len(db.ranges_cm)} readings, "
        f"{path.stat().st_size / 1024:.0f} KiB, map sha256 {db.metadata['map_sha256'][:12]}"
    )


if __name__ == "__main__":
    main()
