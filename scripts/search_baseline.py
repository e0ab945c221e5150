#!/usr/bin/env python
"""The baseline settings search: a grid over the settings both arms share, run on A2C at the paper's protocol.

Every grid point runs ``--epochs`` paper-sized epochs (K learning + M test trials) for each seed
through the experiment runner and is scored by the mean test goal rate over its epochs (the area
under figure 3's curve; ties: reward per step); it prints one row per point with learning
env-steps/s. The grid is what is stated in ``--n-envs`` x ``--learning-rates`` x ``--n-steps`` x
``--ent-coefs``; the other settings are the YAML's.

    OMP_NUM_THREADS=1 nice -n 10 python scripts/search_baseline.py --env NomadOfficeMemorable-v0
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout without installing

from sb3_twodrl.experiments import RunSpec, collect_results, load_hyperparams, run_grid  # noqa: E402
from sb3_twodrl.hyperparams import hyperparams_path  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", default="NomadOfficeMemorable-v0")
    p.add_argument("--algo", default="a2c")
    p.add_argument("--n-envs", type=int, nargs="+", default=[16, 64, 256])
    p.add_argument("--learning-rates", type=float, nargs="+", default=[7e-4, 3e-3])
    p.add_argument("--n-steps", type=int, nargs="+", default=[5])
    p.add_argument("--ent-coefs", type=float, nargs="+", default=None, help="default: the YAML's")
    p.add_argument("--epochs", type=int, default=8)
    p.add_argument("--learn-episodes", "-K", type=int, default=1000)
    p.add_argument("--test-episodes", "-M", type=int, default=100)
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", default="runs/search_baseline")
    args = p.parse_args()
    import envs  # noqa: F401  (registers the IDs)

    base = load_hyperparams(hyperparams_path(args.algo), args.env)
    ent_coefs = args.ent_coefs or [base.get("ent_coef", 0.0)]
    points = list(itertools.product(args.n_envs, args.learning_rates, args.n_steps, ent_coefs))
    specs = []
    for n_envs, lr, n_steps, ent_coef in points:
        hp = {**base, "n_envs": n_envs, "learning_rate": lr, "n_steps": n_steps, "ent_coef": ent_coef}
        out = Path(args.out) / args.env / point_name(n_envs, lr, n_steps, ent_coef)
        for seed in args.seeds:
            spec = RunSpec(
                args.env, args.algo, seed, args.epochs, args.learn_episodes, args.test_episodes, hp, str(out)
            )
            spec.gym_packages, spec.checkpoint_every, spec.tensorboard, spec.save_model = ["envs"], 1, False, False
            specs.append(spec)
    todo = [s for s in specs if not (Path(s.out_dir) / "pairs" / f"{s.name}.csv").exists()]
    run_grid(todo, backend="process", workers=args.workers)
    print(
        f"{args.algo} on {args.env}, {args.epochs} epochs of K={args.learn_episodes}, M={args.test_episodes}, "
        f"seeds {args.seeds}"
    )
    print(
        "| n_envs | learning rate | n_steps | ent_coef | mean test goal rate | per seed | final goal rate per seed "
        "| mean reward per step | first epoch goal rate >= 0.5 (per seed) | env-steps/s of wall time |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n_envs, lr, n_steps, ent_coef in points:
        df = collect_results(Path(args.out) / args.env / point_name(n_envs, lr, n_steps, ent_coef))
        per_seed = df.groupby("seed")["goal_rate"].mean()
        first = [
            str(int(g.loc[g["goal_rate"] >= 0.5, "epoch"].min())) if (g["goal_rate"] >= 0.5).any() else "-"
            for _, g in df.groupby("seed")
        ]
        last = df.sort_values("epoch").groupby("seed").tail(1)
        rate = (last["env_steps"] / last["wall_s"]).mean()
        print(
            f"| {n_envs} | {lr:g} | {n_steps} | {ent_coef:g} | {per_seed.mean():.2f} "
            f"| {', '.join(f'{v:.2f}' for v in per_seed)} | {', '.join(f'{v:.2f}' for v in last['goal_rate'])} "
            f"| {df['reward_per_step'].mean():.3f} | {', '.join(first)} | {rate:,.0f} |"
        )


def point_name(n_envs: int, lr: float, n_steps: int, ent_coef: float) -> str:
    """The grid point's folder (the entropy coefficient named only when it is not 0, as in earlier searches)."""
    name = f"n{n_envs}_lr{lr:g}_s{n_steps}"
    return name if ent_coef == 0 else f"{name}_ent{ent_coef:g}"


if __name__ == "__main__":
    main()
