"""Record a MEMORABLE sensor database: a virtual robot visits every reachable cell of the office.

Our stand-in for a logging run of a real robot: at each reachable lattice cell it takes K
readings of its 16 sonar and 16 IR sensors with the realistic sensor model of
``NomadOfficeReal-v0`` (or exact ones with ``--ideal``). A user with a real robot imports their
log instead: ``python scripts/record_database.py --from-csv log.csv --out my.npz``.

    PYTHONPATH=. python scripts/record_database.py --k 8 --seed 0 --out envs/memorable/data/office_k8.npz
"""

from __future__ import annotations

import argparse
from pathlib import Path

from envs.memorable.database import import_csv, load_database, record_database, save_database
from envs.nomad.office import office_core
from envs.nomad.sensors import NoiseModel


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--k", type=int, default=8, help="readings per cell (default 8)")
    parser.add_argument("--seed", type=int, default=0, help="noise seed of the recording (default 0)")
    parser.add_argument("--map", type=Path, default=None, help="office map JSON (default: the shipped office)")
    parser.add_argument("--ideal", action="store_true", help="record the exact sensors instead of the realistic model")
    parser.add_argument("--from-csv", type=Path, default=None, help="import a CSV log instead of recording")
    parser.add_argument("--allow-missing", action="store_true", help="CSV: allow reachable cells without readings")
    parser.add_argument("--out", type=Path, required=True, help="output .npz")
    args = parser.parse_args(argv)
    if args.from_csv is not None:
        db = import_csv(args.from_csv, map=args.map, require_all_cells=not args.allow_missing)
    else:
        noise = None if args.ideal else NoiseModel()
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
