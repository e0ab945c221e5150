"""``sb3-twodrl-record-database``: check a map and record its MEMORABLE sensor database.

A virtual robot visits every cell of the office reachable from the start. ``--model realistic``
(default): the stand-in robot of ``NomadOfficeReal-v0`` drives to each cell by dead reckoning,
K times, and files each reading (16 sonar, 16 IR) under its odometry's cell, as a real robot
would. ``--model noise``: placed exactly on each cell, K noisy ideal readings; ``--model ideal``:
exact. A user with a real robot imports their log instead (``--from-csv log.csv``).
``--check`` only loads and checks the map (``ValueError`` messages of
:func:`twodrl_envs.nomad.office.office_core`) and prints what the robot sees of it.

    sb3-twodrl-record-database --map my_office.json --check
    sb3-twodrl-record-database --map my_office.json --out my_office_k8.npz
    sb3-twodrl-record-database --map my_office.json --from-csv robot_log.csv --out my_robot.npz
"""

from __future__ import annotations

import argparse
from pathlib import Path

from twodrl_envs.analysis.dilemma import distance_to_goal
from twodrl_envs.analysis.recording import record_database
from twodrl_envs.memorable.database import import_csv, load_database, save_database
from twodrl_envs.nomad.core import OfficeCore, office_core
from twodrl_envs.nomad.geometry import SHIPPED_MAPS, OfficeMap
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import NoiseModel

MODELS = ("realistic", "noise", "ideal")


def _rect(office: OfficeMap, name: str) -> str:
    return "[" + ", ".join(f"{v:g}" for v in office.regions[name]) + "]"


def describe_map(core: OfficeCore) -> str:
    """A few lines on a checked map: size, start, lattice cells, goal, shortest path, route regions."""
    office, lattice = core.office, core.lattice
    x0, y0, x1, y1 = office.bounds
    moves = distance_to_goal(core)[core.start_cell]
    lines = [
        f"map {office.name!r} ({office.source}): OK",
        f"  {x1 - x0:g} x {y1 - y0:g} cm, start ({office.start[0]:g}, {office.start[1]:g}), "
        f"{len(office.walls)} wall segments",
        f"  {len(lattice.cells)} free lattice cells, {int(lattice.reachable.sum())} reachable from the start",
        f"  goal {_rect(office, 'goal')}: {int((core.goal & lattice.reachable).sum())} reachable cells, "
        f"shortest path {moves:.0f} moves",
    ]
    if office.has_routes:
        for name, code in (("shortcut", 1), ("detour", 2)):
            cells = int(((core.route_code == code) & lattice.reachable).sum())
            lines.append(f"  {name} region {_rect(office, name)}: {cells} reachable cells")
    else:
        lines.append("  no route regions: info has no 'route', no route metrics")
    return "\n".join(lines)


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
    parser.add_argument("--k", type=int, default=8, help="readings per cell (default 8)")
    parser.add_argument("--seed", type=int, default=0, help="noise seed of the recording (default 0)")
    parser.add_argument(
        "--model",
        choices=MODELS,
        default="realistic",
        help="realistic: the stand-in robot driving by dead reckoning (default); noise: noisy ideal; ideal: exact",
    )
    parser.add_argument("--from-csv", type=Path, default=None, help="import a CSV log instead of recording")
    parser.add_argument("--allow-missing", action="store_true", help="CSV: allow reachable cells without readings")
    args = parser.parse_args(argv)
    if not args.check:
        if args.out is None:
            parser.error("--out is required (the .npz file to write), unless --check")
        if args.out.suffix != ".npz":
            parser.error(f"--out must end in .npz, got {str(args.out)!r}")
        if not args.out.parent.is_dir():
            parser.error(f"--out: directory {str(args.out.parent)!r} does not exist")
        if args.k < 1:
            parser.error(f"--k must be >= 1, got {args.k}")
    try:
        core = office_core(args.map)
    except (ValueError, TypeError) as err:
        parser.error(f"--map: {err}")
    print(describe_map(core))
    if args.check:
        return
    if args.from_csv is not None:
        try:
            db = import_csv(args.from_csv, map=args.map, require_all_cells=not args.allow_missing)
        except ValueError as err:
            parser.error(f"--from-csv: {err}")
    elif args.model == "realistic":
        db = record_database(args.k, map=args.map, model=RealisticModel(), seed=args.seed)
    else:
        noise = NoiseModel() if args.model == "noise" else None
        db = record_database(args.k, map=args.map, noise=noise, seed=args.seed, progress=True)
    path = save_database(db, args.out)
    load_database(path, core)  # read back strictly
    recorded = int((db.counts > 0).sum())
    print(
        f"wrote {path}: {recorded} cells, {len(db.ranges_cm)} readings, "
        f"{path.stat().st_size / 1024:.0f} KiB, map sha256 {db.metadata['map_sha256'][:12]}"
    )


if __name__ == "__main__":
    main()
