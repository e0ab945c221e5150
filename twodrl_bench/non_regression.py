"""Non-regression against stock SB3 on classic tasks: ``sb3-twodrl-non-regression``.

Each (algo, seed) trains with rl-zoo3 itself (``rl_zoo3.train``, the packaged hyperparameter files of
:mod:`sb3_twodrl.hyperparams` or those of ``--hyperparams-dir``, i.e. rl-zoo3's own entries for stock
A2C and the same entries plus the 2D-RL arguments for TwoDimA2C) in a worker process, then its final
model runs ``--episodes`` deterministic episodes on a fresh env (with the run's ``VecNormalize``
statistics, frozen, where the entry normalises), seeded apart from training. The table gives each algo's
mean return per seed and over seeds with a 95% t-interval, and the difference to the first algo with a
Welch interval.
Requires the ``zoo`` extra.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import multiprocessing as mp
import os
from pathlib import Path
from typing import Any

from sb3_twodrl.hyperparams import hyperparams_path, read_entry
from twodrl_bench.intervals import mean_ci, welch_ci

EVAL_SEED = 10**6
"""Seed of the evaluation env: apart from the training seeds."""


def train_and_evaluate(
    algo: str,
    env_id: str,
    seed: int,
    out: str,
    hyperparams_dir: str | None,
    episodes: int,
    n_timesteps: int | None = None,
    overrides: tuple[str, ...] = (),
) -> float:
    """Train ``algo`` on ``env_id`` with rl-zoo3 (seed ``seed``, logs in ``out``, ``<algo>.yml`` of
    ``hyperparams_dir``, by default the packaged one); its mean evaluation return.

    ``n_timesteps``: the budget, if not the file's (rl-zoo3's ``-n``); ``overrides``: ``KEY:VALUE``
    settings over the file's entry (rl-zoo3's ``--hyperparams``).
    """
    import torch as th
    from rl_zoo3.train import train
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.vec_env import VecNormalize

    from sb3_twodrl.zoo import prepare_zoo_argv, run_zoo_entry
    from twodrl_bench.algos import algo_class

    th.set_num_threads(1)
    log = Path(out) / f"{algo}_seed{seed}"
    argv = ["--algo", algo, "--env", env_id, "--seed", str(seed), "-f", str(log), "--eval-freq", "-1"]
    argv += ["--vec-env", "dummy", "--log-interval", "-1", "--device", "cpu"]
    argv += ["--conf-file", str(hyperparams_path(algo, hyperparams_dir))]
    if n_timesteps is not None:
        argv += ["--n-timesteps", str(n_timesteps)]
    if overrides:
        argv += ["--hyperparams", *overrides]
    run_zoo_entry("train.py", prepare_zoo_argv(argv), train)
    (run,) = sorted((log / algo).glob(f"{env_id}_*"))
    model = algo_class(algo).load(run / f"{env_id}.zip", device="cpu")
    env = make_vec_env(env_id, n_envs=1, seed=EVAL_SEED + seed)
    stats = run / env_id / "vecnormalize.pkl"
    if stats.exists():
        env = VecNormalize.load(str(stats), env)
        env.training, env.norm_reward = False, False
    mean, _ = evaluate_policy(model, env, n_eval_episodes=episodes, deterministic=True)
    return float(mean)


def table(env_id: str, returns: dict[str, list[float]]) -> str:
    """Markdown: per algo the returns per seed, the mean [95% t-interval] and the Welch interval of the difference."""
    base_algo, base = next(iter(returns.items()))
    lines = [f"| {env_id} | per seed | mean [95% CI] | minus {base_algo} [95% Welch CI] |", "|---|---|---|---|"]
    for algo, values in returns.items():
        mean, half, _ = mean_ci(values)
        diff = "-"
        if algo != base_algo:
            d, h = welch_ci(values, base)
            diff = f"{d:+.1f} [{d - h:+.1f}, {d + h:+.1f}]"
        cells = ", ".join(f"{v:.1f}" for v in values)
        lines.append(f"| {algo} | {cells} | {mean:.1f} [{mean - half:.1f}, {mean + half:.1f}] | {diff} |")
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", required=True, help="Gymnasium ID with an entry in every algo's file")
    p.add_argument("--algos", nargs="+", default=["a2c", "twoda2c"], help="the first is the baseline")
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(5)))
    p.add_argument("--episodes", type=int, default=20, help="deterministic evaluation episodes per model")
    p.add_argument("--n-timesteps", type=int, help="training budget (default: each file's n_timesteps)")
    p.add_argument("--hyperparams-dir", help="folder of <algo>.yml (default: the packaged files)")
    p.add_argument(
        "--set",
        nargs="+",
        default=[],
        metavar="KEY:VALUE",
        help="settings over the entry of every algo but the baseline (rl-zoo3's --hyperparams format)",
    )
    p.add_argument("--out", type=Path, default=Path("runs") / "non_regression")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = p.parse_args(argv)
    if len(args.seeds) < 2:
        raise ValueError(f"seeds: an interval needs at least 2, got {args.seeds!r}")
    return args


def settings(args: argparse.Namespace) -> dict[str, str]:
    """What a kept result must agree on, per algo: its file's entry for the env, the budget, the episodes."""
    out = {}
    for algo in args.algos:
        entry = read_entry(hyperparams_path(algo, args.hyperparams_dir), args.env)
        kept = {"entry": entry, "n_timesteps": args.n_timesteps, "episodes": args.episodes}
        if algo != args.algos[0]:
            kept["set"] = sorted(args.set)
        out[algo] = json.dumps(kept, sort_keys=True, default=str)
    return out


def check_settings(out: Path, current: dict[str, str]) -> None:
    """Refuse to resume ``out`` if an algo's kept results were made with other settings; record them."""
    path = out / "settings.json"
    old = json.loads(path.read_text()) if path.exists() else {}
    changed = sorted(a for a in old.keys() & current.keys() if old[a] != current[a])
    if changed:
        raise ValueError(f"{out} holds results of {', '.join(changed)} with other settings; use another --out")
    path.write_text(json.dumps({**old, **current}, indent=1, sort_keys=True))


def open_record(out: Path, current: dict[str, str], name: str) -> tuple[Path, dict[str, Any]]:
    """Make ``out``, check its settings (:func:`check_settings`) and read the kept record ``out / name``
    (``"<algo>_seed<seed>"`` -> result; empty if none): its path and its entries."""
    out.mkdir(parents=True, exist_ok=True)
    check_settings(out, current)
    store = out / name
    return store, json.loads(store.read_text()) if store.exists() else {}


def non_regression(argv: list[str] | None = None) -> dict[str, list[float]]:
    """Run (or resume: finished (algo, seed) results are kept in ``<out>/<env>/returns.json``, with the
    settings they were made with in ``settings.json``) and print the table."""
    args = parse_args(argv)
    out = args.out / args.env
    store, done = open_record(out, settings(args), "returns.json")
    todo = [(a, s) for a in args.algos for s in args.seeds if f"{a}_seed{s}" not in done]
    with cf.ProcessPoolExecutor(max_workers=args.workers, mp_context=mp.get_context("spawn")) as pool:
        shared = (str(out), args.hyperparams_dir, args.episodes, args.n_timesteps)
        overrides = {a: () if a == args.algos[0] else tuple(args.set) for a in args.algos}
        jobs = {pool.submit(train_and_evaluate, a, args.env, s, *shared, overrides[a]): (a, s) for a, s in todo}
        for job in cf.as_completed(jobs):
            algo, seed = jobs[job]
            done[f"{algo}_seed{seed}"] = job.result()
            store.write_text(json.dumps(done, indent=1, sort_keys=True))
            print(f"{algo} seed {seed}: {done[f'{algo}_seed{seed}']:.1f}", flush=True)
    returns = {a: [done[f"{a}_seed{s}"] for s in args.seeds] for a in args.algos}
    text = table(args.env, returns)
    (out / "table.md").write_text(text + "\n")
    print(text)
    return returns


def main(argv: list[str] | None = None) -> None:
    non_regression(argv)
