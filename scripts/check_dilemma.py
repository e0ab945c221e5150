"""Measure the office's dilemma (properties P1-P5, docs/nomad.md) exactly, before any learning, on one or more maps.

Prints, side by side for each map, the figures of :func:`twodrl_envs.analysis.dilemma.measure` (exact
expectations on the lattice, no sampling) and whether properties P1-P5 hold; ``--limits`` adds the
wall-avoiding walks' goal rates by route for other time limits. Takes a few seconds.

    python scripts/check_dilemma.py                       # the default office and the open one
    python scripts/check_dilemma.py --maps my_office.json --time-limit 400
"""

from __future__ import annotations

import argparse

from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.analysis.dilemma import goal_probabilities, measure, properties, wall_avoiding_policy
from twodrl_envs.nomad.core import office_core


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="+", default=["office", "open"], help="map names or files (default: both)")
    parser.add_argument("--time-limit", type=int, default=MAX_EPISODE_STEPS, help="steps (default: the env's)")
    parser.add_argument("--limits", type=int, nargs="*", default=[], help="extra limits for the P5 walks")
    args = parser.parse_args(argv)
    if args.time_limit < 1:
        raise ValueError(f"--time-limit must be >= 1, got {args.time_limit}")
    cores = {name: office_core(name) for name in args.maps}
    results = {name: measure(core, args.time_limit) for name, core in cores.items()}
    print(f"time limit {args.time_limit} steps, gamma 0.9, eq. 11-12 rewards; exact expectations")
    print(f"{'figure':36s}" + "".join(f"{name[-16:]:>18s}" for name in results))
    for key in next(iter(results.values())):
        print(f"{key:36s}" + "".join(f"{m[key]:18.4f}" for m in results.values()))
    for prop in ("P1", "P2", "P3", "P4", "P5"):
        print(f"{prop:36s}" + "".join(f"{properties(m)[prop]!s:>18s}" for m in results.values()))
    for limit in args.limits:
        for name, core in cores.items():
            reached = goal_probabilities(core, wall_avoiding_policy(core), (limit,))[limit]
            share = reached[2] / max(reached.sum(), 1e-300)
            print(f"{name}: wall-avoiding walks, limit {limit}: goal {reached.sum():.4f}, detour share {share:.3f}")
    return results


if __name__ == "__main__":
    main()
