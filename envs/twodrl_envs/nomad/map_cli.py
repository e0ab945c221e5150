"""``sb3-twodrl-map``: write a generated office to a map JSON file, to use as it is or to edit.

The office is :func:`twodrl_envs.nomad.generator.generate_map` of ``--seed`` and ``--size``, the one
``map="generated:SIZE:SEED"`` gives an env; the command checks it as an env does on load and describes it
(as ``sb3-twodrl-record-database --check`` does).

    sb3-twodrl-map --seed 7 --size M --out my_office.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from twodrl_envs.analysis.cli import describe_map
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.generator import SIZES, generate_map


def _seed(text: str) -> int:
    if not (text.isascii() and text.isdigit()):
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}")
    return int(text)


def map_json(data: dict) -> str:
    """A map's JSON text as the shipped maps are laid out: one key, wall or obstacle a line."""
    items = []
    for key, value in data.items():
        if isinstance(value, list) and value and isinstance(value[0], list):
            rows = ",\n    ".join(json.dumps(row) for row in value)
            items.append(f"  {json.dumps(key)}: [\n    {rows}\n  ]")
        else:
            items.append(f"  {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(items) + "\n}\n"


def main(argv: list[str] | None = None) -> None:
    """Parse the arguments, write the office and print its description."""
    parser = argparse.ArgumentParser(
        prog="sb3-twodrl-map", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seed", type=_seed, required=True, help="the office's seed, an integer >= 0")
    classes = ", ".join(f"{name}: {low}-{high}" for name, (low, high) in SIZES.items())
    parser.add_argument(
        "--size",
        choices=tuple(SIZES),
        default="M",
        help=f"size class, moves of the shortest path ({classes}; default M)",
    )
    parser.add_argument("--out", type=Path, required=True, help="the map JSON file to write")
    parser.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    args = parser.parse_args(argv)
    if args.out.suffix != ".json":
        parser.error(f"--out must end in .json, got {str(args.out)!r}")
    if not args.out.parent.is_dir():
        parser.error(f"--out: directory {str(args.out.parent)!r} does not exist")
    if args.out.exists() and not args.force:
        parser.error(f"--out: {str(args.out)!r} exists (pass --force to overwrite it)")
    data = generate_map(args.seed, args.size)
    args.out.write_text(map_json(data))
    print(describe_map(office_core(args.out)))
    print(f"wrote {args.out} (map='generated:{args.size}:{args.seed}' gives an env the same office)")


if __name__ == "__main__":
    main()
