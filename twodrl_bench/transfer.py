"""Paper section 3.5 from the command line (``sb3-twodrl-transfer``): does database training transfer?

For each algorithm and each training env (default: ``NomadOffice-v0``, the idealised simulator,
and ``NomadOfficeMemorable-v0``, the recorded database) train with the same budget and seeds on
the batched env (or load the final models of reproductions, ``--reproduce-dir``), then run the
deterministic policy on the target env (default ``NomadOfficeReal-v0``, the stand-in robot) with
held-out seeds, all trials in one batched call: the paper's 10 real-robot trials (sub-envs 0-9) and
more for intervals (``--trials`` in all). ``--env-kwargs`` go to the target env and the training
env alike (``observe_odometry:False``: sensors only). One row per (algorithm, training env): the
paper's 10 trials per seed, success, shortcut and collision rates over all trials as means over
seeds with 95% t-intervals, the pooled successes with a Wilson interval, and the success rate of
the same policies in their own training env (did they learn at all?).
"""

from __future__ import annotations

import argparse
import importlib
import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import torch as th
from stable_baselines3.common.base_class import BaseAlgorithm

from twodrl_bench.algos import ALGOS, algo_class
from twodrl_bench.epochs import model_path
from twodrl_bench.intervals import mean_ci, wilson
from twodrl_bench.protocol import parse_env_kwargs
from twodrl_bench.trials import tally, trial_outcomes
from twodrl_bench.vec_env import make_test_env, make_train_env

TRAIN_ENVS = ("NomadOffice-v0", "NomadOfficeMemorable-v0")
PAPER_TRIALS = 10
"""Trials on the real robot per policy in the paper (section 3.5)."""


@dataclass
class TransferRow:
    algo: str
    trained_on: str
    seeds: list[int]
    trials_per_seed: int
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    paper_successes: list[int] = field(default_factory=list)
    successes: list[int] = field(default_factory=list)
    shortcut: list[int] = field(default_factory=list)
    collisions: list[int] = field(default_factory=list)
    timeouts: list[int] = field(default_factory=list)
    train_env_success: list[float] = field(default_factory=list)
    train_seconds: list[float] = field(default_factory=list)


def over_seeds(values: list[float]) -> str:
    """``mean [low, high]``: the mean over seeds with its 95% t-interval."""
    mean, half, n = mean_ci(values)
    return "-" if n == 0 else f"{mean:.2f}" if n == 1 else f"{mean:.2f} [{mean - half:.2f}, {mean + half:.2f}]"


def train_policy(
    algo: str, env_id: str, seed: int, timesteps: int, n_envs: int, env_kwargs: dict[str, Any] | None = None, **kwargs
) -> BaseAlgorithm:
    """``algo`` trained ``timesteps`` steps on ``n_envs`` batched ``env_id`` envs (gamma 0.9; 2D: punishment 0.1)."""
    kwargs = {"gamma": 0.9, **kwargs}
    if algo.startswith("twod"):
        kwargs.setdefault("punishment_gamma", 0.1)
    env = make_train_env(env_id, n_envs, seed, env_kwargs=env_kwargs)
    return algo_class(algo)("MlpPolicy", env, seed=seed, device="cpu", **kwargs).learn(timesteps)


def trials(model: BaseAlgorithm, env_id: str, n: int, seed: int, env_kwargs: dict[str, Any] | None = None) -> list[str]:
    """Outcomes of ``n`` deterministic trials on ``env_id`` (sub-env ``i`` seeded ``seed + i``)."""
    env = make_test_env(env_id, n, env_kwargs=env_kwargs)
    try:
        return trial_outcomes(model, env, seed)
    finally:
        env.close()


def table(rows: list[TransferRow]) -> str:
    """Markdown: rates are means over seeds with 95% t-intervals; successes / N pooled with a Wilson interval."""
    lines = [
        f"| algorithm | trained on | paper's {PAPER_TRIALS} trials, successes per seed | success rate | successes / N "
        "(Wilson) | shortcut share of successes | collision rate | time-out rate | success in training env |",
        "|" + " --- |" * 9,
    ]
    for row in rows:
        n = row.trials_per_seed
        k, total = sum(row.successes), n * len(row.seeds)
        lo, hi = wilson(k, total)
        share = f"{sum(row.shortcut) / k:.2f}" if k else "-"
        lines.append(
            f"| {row.algo} | {row.trained_on} | {', '.join(map(str, row.paper_successes))} | "
            f"{over_seeds([x / n for x in row.successes])} | {k} / {total} ({lo:.0%}-{hi:.0%}) | {share} | "
            f"{over_seeds([x / n for x in row.collisions])} | {over_seeds([x / n for x in row.timeouts])} | "
            f"{over_seeds(row.train_env_success)} |"
        )
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="3 seeds, 150k steps, 50 trials (< 10 min, 2 cores)")
    p.add_argument("--timesteps", type=int, default=300_000, help="training steps per run")
    p.add_argument("--seeds", type=int, default=5, help="training seeds 0..S-1")
    p.add_argument("--seed-list", type=int, nargs="+", help="explicit training seeds (overrides --seeds)")
    p.add_argument("--trials", type=int, default=60, help="target-env trials per policy (the first 10: the paper's)")
    p.add_argument("--eval-seed", type=int, default=1_000_003, help="held-out seed of the target env's trials")
    p.add_argument("--algos", nargs="+", default=["twoda2c", "a2c"], choices=sorted(ALGOS))
    p.add_argument("--train-envs", nargs="+", default=list(TRAIN_ENVS))
    p.add_argument("--target-env", default="NomadOfficeReal-v0")
    p.add_argument("--reproduce-dir", type=Path, help="load <dir>/<train env>/models/<algo>_seed<s>.zip, no training")
    p.add_argument("--n-envs", type=int, default=16)
    p.add_argument("--n-steps", type=int, default=8)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--ent-coef", type=float, default=0.001)
    p.add_argument("--env-kwargs", nargs="*", metavar="KEY:VALUE", help="env arguments, e.g. observe_odometry:False")
    p.add_argument("--gym-packages", nargs="*", default=["envs"], help="modules that register the envs")
    p.add_argument("--json", type=Path, help="also write the rows as JSON")
    args = p.parse_args(argv)
    if args.quick:
        args.timesteps, args.seeds, args.trials = 150_000, 3, 50
    if args.trials < PAPER_TRIALS:
        raise ValueError(f"trials must be at least the paper's {PAPER_TRIALS}, got {args.trials}")
    args.env_kwargs = parse_env_kwargs(args.env_kwargs)
    return args


def transfer(args: argparse.Namespace) -> list[TransferRow]:
    for package in args.gym_packages:
        importlib.import_module(package)
    th.set_num_threads(1)
    seeds = args.seed_list if args.seed_list else list(range(args.seeds))
    rows, start, kwargs = [], time.time(), args.env_kwargs
    for algo in args.algos:
        for env_id in args.train_envs:
            row = TransferRow(algo, env_id, seeds, args.trials, kwargs)
            for seed in seeds:
                t0 = time.time()
                if args.reproduce_dir is None:
                    hp = {"n_steps": args.n_steps, "learning_rate": args.lr, "ent_coef": args.ent_coef}
                    model = train_policy(algo, env_id, seed, args.timesteps, args.n_envs, kwargs, **hp)
                else:
                    model = algo_class(algo).load(model_path(args.reproduce_dir / env_id, f"{algo}_seed{seed}"))
                row.train_seconds.append(round(time.time() - t0, 1))
                own = tally(trials(model, env_id, 10, args.eval_seed + 10**4, kwargs))
                row.train_env_success.append(own["success"] / 10)
                outcomes = trials(model, args.target_env, args.trials, args.eval_seed, kwargs)
                row.paper_successes.append(tally(outcomes[:PAPER_TRIALS])["success"])
                real = tally(outcomes)
                for key, values in (("success", row.successes), ("shortcut", row.shortcut)):
                    values.append(real[key])
                row.collisions.append(real["collision"])
                row.timeouts.append(real["timeout"])
                print(f"  {algo:8s} {env_id:24s} seed {seed}: own env {own['success']}/10, target {real}", flush=True)
            rows.append(row)
    budget = f"final models of {args.reproduce_dir}" if args.reproduce_dir else f"{args.timesteps} training steps"
    print(
        f"\nTransfer to {args.target_env} {kwargs or ''}: {budget}, seeds {seeds}, {args.trials} deterministic trials "
        f"(held-out seed {args.eval_seed})\n\n{table(rows)}\n\ntotal {time.time() - start:.0f} s"
    )
    if args.json is not None:
        args.json.write_text(json.dumps([asdict(r) for r in rows], indent=1))
    return rows


def main(argv: list[str] | None = None) -> None:
    transfer(parse_args(argv))
