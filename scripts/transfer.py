"""Paper section 3.5: does training from recorded readings (MEMORABLE) transfer to the "real" robot?

For each algorithm (TwoDimA2C, stock A2C) and each training env, (a) ``NomadOffice-v0``
(idealised simulator) and (b) ``NomadOfficeMemorable-v0`` (the shipped database of recorded
readings), train with the same budget and seeds, then run the deterministic policy for N trials
on ``NomadOfficeReal-v0`` (sensor noise, sonar drop-outs, motion slip) with a held-out noise
seed. Prints one row per (algorithm, training env): successes / trials pooled over seeds with a
95 % Wilson interval, successes per seed, shortcut share among successes, collisions, time-outs,
and the success rate of the same policies in their own training env (did they learn at all?).

    PYTHONPATH=. python scripts/transfer.py --quick          # < 10 min on 2 cores
    PYTHONPATH=. python scripts/transfer.py                  # 5 seeds, 100 trials, 300k steps
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch as th
from stable_baselines3 import A2C

import envs  # noqa: F401  (registers the IDs)
from envs.memorable.env import make_memorable_vec_env
from envs.nomad.batched import make_sb3_vec_env
from sb3_twodrl import TwoDimA2C

TRAIN_ENVS = {"NomadOffice-v0": make_sb3_vec_env, "NomadOfficeMemorable-v0": make_memorable_vec_env}
ALGOS = {"TwoDimA2C": TwoDimA2C, "A2C": A2C}


@dataclass
class Row:
    algo: str
    trained_on: str
    seeds: list[int]
    trials_per_seed: int
    successes: list[int] = field(default_factory=list)
    shortcut: list[int] = field(default_factory=list)
    collisions: list[int] = field(default_factory=list)
    timeouts: list[int] = field(default_factory=list)
    train_env_success: list[float] = field(default_factory=list)
    train_seconds: list[float] = field(default_factory=list)


def wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """95 % Wilson score interval of a proportion k / n."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def run_trials(model, env_id: str, trials: int, seed: int) -> dict[str, int]:
    """Deterministic policy for ``trials`` episodes; the env is seeded once, then reset freely."""
    env = gym.make(f"envs:{env_id}")
    counts = {"success": 0, "shortcut": 0, "collision": 0, "timeout": 0}
    obs, _ = env.reset(seed=seed)
    for _ in range(trials):
        done = False
        while not done:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, terminated, truncated, info = env.step(int(action))
            done = terminated or truncated
        if info["is_success"]:
            counts["success"] += 1
            counts["shortcut"] += info["route"] == "shortcut"
        elif info["collision"]:
            counts["collision"] += 1
        else:
            counts["timeout"] += 1
        obs, _ = env.reset()
    env.close()
    return counts


def train(algo: str, env_id: str, seed: int, args: argparse.Namespace):
    venv = TRAIN_ENVS[env_id](args.n_envs, seed=seed)
    kwargs = dict(
        gamma=0.9, n_steps=args.n_steps, learning_rate=args.lr, ent_coef=args.ent_coef, seed=seed, device="cpu"
    )
    if algo == "TwoDimA2C":
        kwargs["punishment_gamma"] = 0.1
    model = ALGOS[algo]("MlpPolicy", venv, **kwargs)
    model.learn(args.timesteps)
    return model


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="3 seeds, 150k steps, 50 trials (< 10 min, 2 cores)")
    parser.add_argument("--timesteps", type=int, default=300_000, help="training steps per run")
    parser.add_argument("--seeds", type=int, default=5, help="training seeds 0..S-1")
    parser.add_argument("--trials", type=int, default=100, help="trials on NomadOfficeReal-v0 per trained policy")
    parser.add_argument("--eval-seed", type=int, default=1_000_003, help="held-out noise seed of the real robot")
    parser.add_argument("--algos", default="TwoDimA2C,A2C")
    parser.add_argument("--n-envs", type=int, default=16)
    parser.add_argument("--n-steps", type=int, default=8)
    parser.add_argument("--lr", type=float, default=1e-3)
    parser.add_argument("--ent-coef", type=float, default=0.001)
    parser.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    args = parser.parse_args(argv)
    if args.quick:
        args.timesteps, args.seeds, args.trials = 150_000, 3, 50
    th.set_num_threads(1)
    seeds = list(range(args.seeds))
    rows = []
    start = time.time()
    for algo in args.algos.split(","):
        for env_id in TRAIN_ENVS:
            row = Row(algo, env_id, seeds, args.trials)
            for seed in seeds:
                t0 = time.time()
                model = train(algo, env_id, seed, args)
                row.train_seconds.append(round(time.time() - t0, 1))
                own = run_trials(model, env_id, 10, seed=args.eval_seed + 1)
                row.train_env_success.append(own["success"] / 10)
                real = run_trials(model, "NomadOfficeReal-v0", args.trials, seed=args.eval_seed)
                row.successes.append(real["success"])
                row.shortcut.append(real["shortcut"])
                row.collisions.append(real["collision"])
                row.timeouts.append(real["timeout"])
                print(
                    f"  {algo:9s} {env_id:24s} seed {seed}: own env {own['success']}/10, real {real}"
                    f"  ({time.time() - start:.0f} s)",
                    flush=True,
                )
            rows.append(row)
    print(
        f"\nTransfer to NomadOfficeReal-v0: {args.timesteps} training steps, seeds {seeds}, {args.trials} trials "
        f"per policy (held-out noise seed {args.eval_seed}), deterministic policies; "
        f"n_envs={args.n_envs} n_steps={args.n_steps} lr={args.lr} ent_coef={args.ent_coef}, gamma 0.9 "
        f"(TwoDimA2C: punishment_gamma 0.1)\n"
    )
    header = (
        "| algorithm | trained on | successes / N | 95 % Wilson CI | per seed | shortcut share | collisions "
        "| time-outs | success in training env |"
    )
    print(header)
    print("|" + " --- |" * 9)
    for row in rows:
        n = args.trials * len(seeds)
        k = sum(row.successes)
        lo, hi = wilson(k, n)
        share = f"{sum(row.shortcut) / k:.2f}" if k else "-"
        print(
            f"| {row.algo} | {row.trained_on} | {k} / {n} ({k / n:.0%}) | {lo:.0%}-{hi:.0%} | "
            f"{', '.join(map(str, row.successes))} | {share} | {sum(row.collisions)} | {sum(row.timeouts)} | "
            f"{np.mean(row.train_env_success):.0%} |"
        )
    print(f"\ntotal {time.time() - start:.0f} s")
    if args.json is not None:
        args.json.write_text(json.dumps([asdict(r) for r in rows], indent=1))


if __name__ == "__main__":
    main()
