"""A baseline's settings search at the paper's protocol: ``sb3-twodrl-search``.

A grid over settings of one algorithm's hyperparameter entry (``--grid KEY:V1,V2 ...``, the rest
of the entry as packaged or changed by ``--set KEY:VALUE``), each point run for ``--epochs`` paper
epochs (K learning + M test trials) per seed through the experiment runner. Each point is scored
two ways: the mean test goal rate over all its epochs (the area under figure 3's curve) and the
mean test reward per step over the epochs ``--score-epochs FIRST LAST``; ``--rank-by`` names the
score that picks the point, the other breaks ties. Finished (point, seed) runs are kept and not run again.
"""

from __future__ import annotations

import argparse
import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np

from sb3_twodrl.hyperparams import hyperparams_path
from twodrl_bench.grid import collect_results, pending, run_grid
from twodrl_bench.protocol import RunSpec, load_hyperparams, parse_env_kwargs

SCORES = ("goal_rate", "reward_per_step")


def parse_grid(items: list[str]) -> dict[str, list[Any]]:
    """``["learning_rate:3e-4,1e-3", "n_epochs:4,10"]`` -> ``{"learning_rate": [3e-4, 1e-3], "n_epochs": [4, 10]}``."""
    keys = [item.partition(":")[0] for item in items]
    if len(set(keys)) < len(keys):
        raise ValueError(f"grid: a key given twice in {items!r}")
    return {k: list(v) if isinstance(v, tuple) else [v] for k, v in parse_env_kwargs(items, "grid").items()}


def point_name(point: dict[str, Any]) -> str:
    """A grid point's folder: ``key=value`` pairs in grid order."""
    return "_".join(
        f"{key}={value:g}" if isinstance(value, float) else f"{key}={value}" for key, value in point.items()
    )


def score(rows: Any, first: int, last: int) -> dict[str, Any]:
    """One point's rows (every seed): both scores, per seed and averaged, and each seed's first epoch at a
    test goal rate >= 0.5 (``None``: never)."""
    per_seed = {}
    for seed, g in rows.groupby("seed"):
        window = g.loc[g["epoch"].between(first, last), "reward_per_step"].to_numpy(dtype=float)
        half = g.loc[g["goal_rate"] >= 0.5, "epoch"]
        per_seed[int(seed)] = {
            "goal_rate": float(g["goal_rate"].mean()),
            "reward_per_step": float(window.mean()) if window.size else math.nan,
            "first_half": int(half.min()) if len(half) else None,
        }
    means = {key: float(np.mean([s[key] for s in per_seed.values()])) for key in SCORES}
    return {**means, "per_seed": per_seed}


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", default="NomadOffice-v0")
    p.add_argument("--algo", default="a2c", help="the baseline, a name of twodrl_bench.ALGOS")
    p.add_argument("--grid", nargs="+", required=True, metavar="KEY:V1,V2", help="the settings searched")
    p.add_argument("--set", nargs="*", default=[], metavar="KEY:VALUE", help="settings changed at every point")
    p.add_argument("--epochs", type=int, default=20)
    p.add_argument("--learn-episodes", "-K", type=int, default=1000)
    p.add_argument("--test-episodes", "-M", type=int, default=100)
    p.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102])
    p.add_argument("--score-epochs", type=int, nargs=2, metavar=("FIRST", "LAST"), help="default: the last half")
    p.add_argument("--rank-by", choices=SCORES, default="reward_per_step")
    p.add_argument("--gym-packages", nargs="*", default=["envs"], help="modules that register the env")
    p.add_argument("--backend", choices=("process", "serial"), default="process")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", type=Path, default=Path("runs") / "search")
    args = p.parse_args(argv)
    first, last = args.score_epochs or (args.epochs // 2 + 1, args.epochs)
    if not 1 <= first <= last <= args.epochs:
        raise ValueError(f"score_epochs must satisfy 1 <= FIRST <= LAST <= epochs, got {first} {last}")
    args.score_epochs = (first, last)
    return args


def search(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Run (or resume) the grid; print its table, best point first; the points with their scores."""
    args = parse_args(argv)
    grid = parse_grid(args.grid)
    base = {**load_hyperparams(hyperparams_path(args.algo), args.env), **parse_env_kwargs(args.set, "set")}
    points = [dict(zip(grid, values, strict=True)) for values in itertools.product(*grid.values())]
    folders = [args.out / args.env / args.algo / point_name(point) for point in points]
    specs = []
    for point, folder in zip(points, folders, strict=True):
        for seed in args.seeds:
            spec = RunSpec(
                args.env,
                args.algo,
                seed,
                args.epochs,
                args.learn_episodes,
                args.test_episodes,
                {**base, **point},
                str(folder),
                gym_packages=args.gym_packages,
                checkpoint_every=1,
                save_model=False,
                tensorboard=False,
            )
            specs.append(spec)
    run_grid(pending(specs), args.backend, args.workers)
    first, last = args.score_epochs
    results = [
        {**point, **score(collect_results(folder), first, last)} for point, folder in zip(points, folders, strict=True)
    ]
    results.sort(key=lambda r: tuple(-r[k] if math.isfinite(r[k]) else math.inf for k in _ranking(args.rank_by)))
    print(table(results, list(grid), args, first, last))
    return results


def _ranking(rank_by: str) -> tuple[str, ...]:
    """The scores in the order they rank points: ``rank_by``, then the other (ties)."""
    return (rank_by, *(k for k in SCORES if k != rank_by))


def table(results: list[dict[str, Any]], keys: list[str], args: argparse.Namespace, first: int, last: int) -> str:
    """Markdown: one row per point, best first, with both scores per seed."""
    head = (
        f"{args.algo} on {args.env}, {args.epochs} epochs of K={args.learn_episodes}, M={args.test_episodes}, "
        f"seeds {args.seeds}, ranked by {args.rank_by}\n\n"
    )
    cols = [*keys, "mean test goal rate", f"reward per step, epochs {first}-{last}", "per seed", "first epoch >= 0.5"]
    lines = ["| " + " | ".join(cols) + " |", "|---" * len(cols) + "|"]
    for r in results:
        seeds = r["per_seed"].values()
        cells = [f"{r[k]:g}" if isinstance(r[k], float) else str(r[k]) for k in keys]
        cells += [f"{r['goal_rate']:.2f}", f"{r['reward_per_step']:.4f}"]
        cells.append(", ".join(f"{s['reward_per_step']:.4f}" for s in seeds))
        cells.append(", ".join("-" if s["first_half"] is None else str(s["first_half"]) for s in seeds))
        lines.append("| " + " | ".join(cells) + " |")
    return head + "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    search(argv)
