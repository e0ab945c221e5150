"""Record a MEMORABLE sensor database: a virtual robot visits every reachable cell of the office.

Our stand-in for a logging run of a real robot. ``--model realistic`` (default): the stand-in
robot of ``NomadOfficeReal-v0`` drives to each reachable cell by dead reckoning, K times, and
files each reading (16 sonar, 16 IR) under its odometry's cell, as a real robot would.
``--model noise``: placed exactly on each cell, K noisy ideal readings; ``--model ideal``: exact.
A user with a real robot imports their log instead:
``python scripts/record_database.py --from-csv log.csv --out my.npz``.

    PYTHONPATH=. python scripts/record_database.py --k 8 --seed 0 --out envs/memorable/data/office_k8.npz
"""

from __future__ import annotations

import argparse
from pathlib import Path

from envs.memorable.database import import_csv, load_database, record_database, save_database
from envs.nomad.office import office_core
from envs.nomad.realistic import RealisticModel
from envs.nomad.sensors import NoiseModel


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--k", type=int, default=8, help="readings per cell (default 8)")
    parser.add_argument("--seed", type=int, default=0, help="noise seed of the recording (default 0)")
    parser.add_argument("--map", type=Path, default=None, help="office map JSON (default: the shipped office)")
    parser.add_argument(
        "--model",
        choices=("realistic", "noise", "ideal"),
        default="realistic",
        help="realistic: the stand-in robot driving by dead reckoning (default); noise: noisy ideal; ideal: exact",
    )
    parser.add_argument("--ideal", action="store_true", help="same as --model ideal")
    parser.add_argument("--from-csv", type=Path, default=None, help="import a CSV log instead of recording")
    parser.add_argument("--allow-missing", action="store_true", help="CSV: allow reachable cells without readings")
    parser.add_argument("--out", type=Path, required=True, help="output .npz")
    args = parser.parse_args(argv)
    if args.from_csv is not None:
        db = import_csv(args.from_csv, map=args.map, require_all_cells=not args.allow_missing)
    elif args.model == "realistic" and not args.ideal:
        db = record_database(args.k, map=args.map, model=RealisticModel(), seed=args.seed)
    else:
        noise = None if args.ideal or args.model == "ideal" else NoiseModel()
        db = record_database(args.k, map=args.map, noise=noise, seed=args.seed, progress=True)
    path = save_database(db, args.out)
    load_database(path, office_core(args.map))  # read back strictly
    recorded = int((db.counts > 0).sum())
    print(
        f"wrote {path}: {recorded} cells, {len(db.ranges_cm)} readings, "
        f"{path.stat().st_size / 1024:.0f} KiB, map sha256 {db.metadata['map_sha256'][:12]}"
    )


if __name__ == "__main__":
    main()
