#!/usr/bin/env python
"""Reproduce the 2D-RL paper's experiment (section 3.4, figures 3-5): TwoDimA2C vs stock A2C, many seeds.

Protocol (paper, section 3.4.1): an *epoch* is K learning episodes ("trials"; paper: 1000)
followed by M test episodes (paper: 100) run with different random numbers, from which the goal
rate, the reward per step and the route shares are measured. Both algorithms train with the
paper's discounts (A2C: gamma 0.9; TwoDimA2C: gamma 0.9, punishment gamma 0.1) and the rest of
the settings of ``scripts/hyperparams/<algo>.yml`` (the env's entry, else ``NomadOffice-v0``'s).

Choices where the paper is silent:

- Learning goes on in one ``learn()`` call per (algo, seed); a callback pauses it after every K
  finished learning episodes (counted over all parallel envs) to run the test episodes, so no
  collected experience is thrown away at epoch boundaries.
- Test episodes use the *stochastic* policy (``predict(deterministic=False)``): the paper's robot
  keeps acting by eq. 9 in its test trials. For TwoDimA2C the temperature is then its running
  interest estimate. M test environments run one episode each, seeded per (seed, epoch) with
  seeds disjoint from the training seeds; the policy's sampling uses its own torch/numpy random
  state, which is restored afterwards, so testing does not perturb the learning run.
- Metrics are those of :func:`sb3_twodrl.callbacks.summarize_episodes` over the M test episodes;
  ``env_steps`` counts learning steps only; ``wall_s`` is the time since the (algo, seed) run began.

Outputs under ``--out`` (default ``runs/reproduce/<env>``): ``results.csv`` (tidy: one row per
algo, seed, epoch), ``pairs/<algo>_seed<seed>.csv`` (one per finished run: what resuming checks),
``tb/<algo>_seed<seed>_1`` (TensorBoard: SB3's keys, ``rollout/*`` metrics, ``test/*`` per epoch),
``fig3_goal_rate.png``, ``fig4_reward_per_step.png``, ``fig5_route_share.png``, ``summary.md``.

Backends: ``process`` (default) runs the (algo, seed) pairs in ``--workers`` worker processes;
``ray`` runs them as Ray tasks (``--ray-address`` of a cluster, default: a local Ray instance).
Ray workers must be able to import ``sb3_twodrl`` and the env package (install the project on
every node); their TensorBoard logs stay on the node that ran them unless ``--out`` is on a
shared file system. The CSV is written by the driver either way.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import importlib
import json
import math
import multiprocessing as mp
import os
import random
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout without installing
sys.path.insert(1, str(ROOT / "scripts"))  # plots.py
HYPERPARAMS_DIR = ROOT / "scripts" / "hyperparams"
METRICS = ("goal_rate", "reward_per_step", "shortcut_share", "detour_share", "collision_rate")
COLUMNS = ["env", "algo", "seed", "epoch", "learn_episodes", *METRICS, "env_steps", "wall_s"]
PRESETS: dict[str, dict[str, int]] = {
    # epochs, learning episodes per epoch (K), test episodes per epoch (M), seeds (S)
    "tiny": {"epochs": 3, "learn_episodes": 8, "test_episodes": 4, "seeds": 2},
    "quick": {"epochs": 20, "learn_episodes": 150, "test_episodes": 50, "seeds": 3},
    "paper": {"epochs": 1000, "learn_episodes": 1000, "test_episodes": 100, "seeds": 5},
}


@dataclass
class RunSpec:
    """Everything one (algo, seed) run needs; plain data, so it can travel to a worker process."""

    env_id: str
    algo: str
    seed: int
    epochs: int
    learn_episodes: int
    test_episodes: int
    hyperparams: dict[str, Any]
    out_dir: str
    gym_packages: list[str] = field(default_factory=list)
    progress_file: str | None = None


# ----------------------------------------------------------------------------------------------
# One (algo, seed) run
# ----------------------------------------------------------------------------------------------


def algo_class(algo: str):
    if algo == "a2c":
        from stable_baselines3 import A2C

        return A2C
    if algo == "twoda2c":
        from sb3_twodrl import TwoDimA2C  # type: ignore[attr-defined]

        return TwoDimA2C
    raise ValueError(f"unknown algo {algo!r}: expected 'a2c' or 'twoda2c'")


def load_hyperparams(algo: str, env_id: str, hyperparams_dir: Path = HYPERPARAMS_DIR) -> dict[str, Any]:
    """The env's entry of ``<algo>.yml`` (else ``NomadOffice-v0``'s), minus what only rl-zoo3 uses."""
    import yaml

    conf = yaml.safe_load((Path(hyperparams_dir) / f"{algo}.yml").read_text())
    entry = dict(conf.get(env_id) or conf["NomadOffice-v0"])
    for key in ("n_timesteps", "callback", "normalize", "env_wrapper", "vec_env_wrapper", "frame_stack"):
        entry.pop(key, None)
    if isinstance(entry.get("policy_kwargs"), str):
        import torch  # noqa: F401  (names available to eval, as rl-zoo3 does)
        from torch import nn  # noqa: F401

        entry["policy_kwargs"] = eval(entry["policy_kwargs"])
    for key, value in entry.items():
        if isinstance(value, str) and value.startswith(("lin_", "linear_")):
            raise ValueError(f"{key}: schedules are not supported by reproduce.py, got {value!r}")
    return entry


def eval_seed(seed: int, epoch: int) -> int:
    """Seeds of the test episodes: disjoint from the training seeds (which are < 10**6)."""
    return 10**6 + 1_000 * (seed % 10**6) + epoch


def make_train_env(env_id: str, n_envs: int, seed: int):
    from stable_baselines3.common.env_util import make_vec_env

    return make_vec_env(env_id, n_envs=n_envs, seed=seed)


def make_test_env(env_id: str, n_envs: int):
    import gymnasium as gym
    from stable_baselines3.common.vec_env import DummyVecEnv

    return DummyVecEnv([lambda: gym.make(env_id)] * n_envs)


def run_test_episodes(model, test_env, seed: int) -> dict[str, float]:
    """One episode in each of the test env's sub-envs with the stochastic policy; summarised metrics."""
    import numpy as np
    import torch

    from sb3_twodrl.callbacks import EpisodeTracker, summarize_episodes

    n = test_env.num_envs
    np_state, py_state = np.random.get_state(), random.getstate()
    try:
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            np.random.seed(seed % 2**32)
            random.seed(seed)
            test_env.seed(seed)
            obs = test_env.reset()
            tracker = EpisodeTracker(n)
            records: list[Any] = [None] * n
            while any(r is None for r in records):
                actions, _ = model.predict(obs, deterministic=False)
                obs, rewards, dones, infos = test_env.step(actions)
                before = [i for i in range(n) if dones[i]]
                finished = tracker.step(infos, dones, rewards)
                for i, rec in zip(before, finished, strict=True):
                    if records[i] is None:
                        records[i] = rec
    finally:
        np.random.set_state(np_state)
        random.setstate(py_state)
    return summarize_episodes(records)


def run_pair(spec: RunSpec) -> list[dict[str, Any]]:
    """Train one algorithm with one seed for ``spec.epochs`` epochs; returns the CSV rows."""
    import numpy as np
    import torch
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.utils import set_random_seed

    from sb3_twodrl.callbacks import NavigationMetricsCallback

    for package in spec.gym_packages:
        importlib.import_module(package)
    torch.set_num_threads(1)
    set_random_seed(spec.seed)
    start = time.perf_counter()

    hp = dict(spec.hyperparams)
    n_envs = int(hp.pop("n_envs", 1))
    policy = hp.pop("policy", "MlpPolicy")
    env = make_train_env(spec.env_id, n_envs, spec.seed)
    test_env = make_test_env(spec.env_id, spec.test_episodes)
    tb_root = Path(spec.out_dir) / "tb"
    run_name = f"{spec.algo}_seed{spec.seed}"
    for stale in tb_root.glob(f"{run_name}_*"):  # an interrupted earlier attempt of this pair
        shutil.rmtree(stale, ignore_errors=True)
    model = algo_class(spec.algo)(policy, env, seed=spec.seed, device="cpu", tensorboard_log=str(tb_root), **hp)
    rows: list[dict[str, Any]] = []
    progress = Path(spec.progress_file) if spec.progress_file else None
    if progress is not None:
        progress.parent.mkdir(parents=True, exist_ok=True)
        progress.write_text("")

    class Epochs(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.episodes = 0
            self.epoch = 0

        def _on_step(self) -> bool:
            self.episodes += int(np.sum(self.locals["dones"]))
            while self.episodes >= (self.epoch + 1) * spec.learn_episodes and self.epoch < spec.epochs:
                self.epoch += 1
                metrics = run_test_episodes(self.model, test_env, eval_seed(spec.seed, self.epoch))
                row = {
                    "env": spec.env_id,
                    "algo": spec.algo,
                    "seed": spec.seed,
                    "epoch": self.epoch,
                    "learn_episodes": self.epoch * spec.learn_episodes,
                    **{key: metrics.get(key, math.nan) for key in METRICS},
                    "env_steps": int(self.num_timesteps),
                    "wall_s": round(time.perf_counter() - start, 3),
                }
                rows.append(row)
                for key in METRICS:
                    self.logger.record(f"test/{key}", row[key])
                self.logger.record("test/epoch", self.epoch)
                self.logger.dump(self.num_timesteps)
                if progress is not None:
                    with progress.open("a") as f:
                        f.write(f"{self.epoch}\n")
            return self.epoch < spec.epochs

    model.learn(
        total_timesteps=10**15,
        callback=[NavigationMetricsCallback(), Epochs()],
        tb_log_name=run_name,
        log_interval=100,
    )
    env.close()
    test_env.close()
    return rows


# ----------------------------------------------------------------------------------------------
# The grid: resume, backends, progress
# ----------------------------------------------------------------------------------------------


def pair_csv(out: Path, algo: str, seed: int) -> Path:
    return out / "pairs" / f"{algo}_seed{seed}.csv"


def write_rows(path: Path, rows: list[dict[str, Any]]) -> None:
    """Write atomically (temporary file, then rename), so a finished file is always complete."""
    import csv

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    os.replace(tmp, path)


def collect_results(out: Path):
    import pandas as pd

    files = sorted((out / "pairs").glob("*.csv"))
    if not files:
        return pd.DataFrame(columns=COLUMNS)
    df = pd.concat([pd.read_csv(f) for f in files], ignore_index=True)
    return df.sort_values(["algo", "seed", "epoch"]).reset_index(drop=True)[COLUMNS]


def check_config(out: Path, config: dict[str, Any]) -> None:
    """A resumed run must use the protocol of the first one (seeds and algos may be added).

    The algos of an earlier invocation stay part of the config that is written back.
    """
    path = out / "config.json"
    if path.exists():
        old = json.loads(path.read_text())
        old_hyperparams = old.get("hyperparams", {})
        diff = [k for k in ("env_id", "epochs", "learn_episodes", "test_episodes") if old.get(k) != config.get(k)]
        diff += [
            f"hyperparams of {algo}"
            for algo in sorted(old_hyperparams.keys() & config["hyperparams"].keys())
            if old_hyperparams[algo] != config["hyperparams"][algo]
        ]
        if diff:
            raise SystemExit(f"{out} holds a run with other settings ({', '.join(diff)}); use another --out")
        config = {**config, "hyperparams": {**old_hyperparams, **config["hyperparams"]}}
    out.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(config, indent=2, sort_keys=True))


def run_grid(
    specs: list[RunSpec], backend: str = "process", workers: int = 2, ray_address: str | None = None, bar=None
) -> dict[tuple[str, int], list[dict[str, Any]]]:
    """Run the specs in parallel; each finished pair's rows are written to its pair CSV at once."""
    results: dict[tuple[str, int], list[dict[str, Any]]] = {}
    if not specs:
        return results
    epochs_done = {(s.algo, s.seed): 0 for s in specs}

    def finish(spec: RunSpec, rows: list[dict[str, Any]]) -> None:
        write_rows(pair_csv(Path(spec.out_dir), spec.algo, spec.seed), rows)
        results[(spec.algo, spec.seed)] = rows
        if spec.progress_file and os.path.exists(spec.progress_file):
            os.remove(spec.progress_file)
        if bar is not None:
            bar.update(spec.epochs - epochs_done[(spec.algo, spec.seed)])
            epochs_done[(spec.algo, spec.seed)] = spec.epochs

    def poll(pending_specs: list[RunSpec]) -> None:
        if bar is None:
            return
        for s in pending_specs:
            if s.progress_file and os.path.exists(s.progress_file):
                with open(s.progress_file) as f:
                    n = sum(1 for _ in f)
                key = (s.algo, s.seed)
                if n > epochs_done[key]:
                    bar.update(n - epochs_done[key])
                    epochs_done[key] = n

    if backend == "process":
        ctx = mp.get_context("spawn")
        with cf.ProcessPoolExecutor(max_workers=max(1, workers), mp_context=ctx) as pool:
            futures = {pool.submit(run_pair, s): s for s in specs}
            pending = set(futures)
            while pending:
                done, pending = cf.wait(pending, timeout=2.0, return_when=cf.FIRST_COMPLETED)
                for fut in done:
                    finish(futures[fut], fut.result())
                poll([futures[f] for f in pending])
    elif backend == "ray":
        import ray

        init_kwargs: dict[str, Any] = {"ignore_reinit_error": True, "include_dashboard": False}
        if ray_address:
            init_kwargs["address"] = ray_address
        else:
            # a local Ray instance: workers find this checkout like the driver does
            init_kwargs["num_cpus"] = max(1, workers)
            init_kwargs["runtime_env"] = {"env_vars": {"PYTHONPATH": os.pathsep.join([str(ROOT), *sys.path[1:]])}}
        started_here = not ray.is_initialized()
        ray.init(**init_kwargs)
        try:
            remote = ray.remote(num_cpus=1, max_retries=0)(run_pair)
            refs = {remote.remote(s): s for s in specs}
            pending = list(refs)
            while pending:
                done, pending = ray.wait(pending, num_returns=1, timeout=2.0)
                for ref in done:
                    finish(refs[ref], ray.get(ref))
                poll([refs[r] for r in pending])
        finally:
            if started_here:
                ray.shutdown()
    elif backend == "serial":
        for s in specs:
            finish(s, run_pair(s))
    else:
        raise ValueError(f"unknown backend {backend!r}")
    return results


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--env", default="NomadOfficeMemorable-v0", help="Gymnasium ID (default: %(default)s)")
    p.add_argument("--preset", choices=sorted(PRESETS), default="quick", help="protocol size (default: %(default)s)")
    p.add_argument("--epochs", type=int, help="epochs (overrides the preset)")
    p.add_argument("--learn-episodes", "-K", type=int, help="learning episodes per epoch, K (overrides the preset)")
    p.add_argument("--test-episodes", "-M", type=int, help="test episodes per epoch, M (overrides the preset)")
    p.add_argument("--seeds", "-S", type=int, help="number of seeds, 0..S-1 (overrides the preset)")
    p.add_argument("--seed-list", type=int, nargs="+", help="explicit seeds (overrides --seeds)")
    p.add_argument("--algos", nargs="+", default=["twoda2c", "a2c"], choices=["twoda2c", "a2c"])
    p.add_argument("--n-envs", type=int, help="parallel learning envs (default: the hyperparams file's n_envs)")
    p.add_argument("--hyperparams-dir", default=str(HYPERPARAMS_DIR))
    p.add_argument("--out", help="output folder (default: runs/reproduce/<env>)")
    p.add_argument("--backend", choices=["process", "ray", "serial"], default="process")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="parallel runs (default: CPU count)")
    p.add_argument("--ray-address", help="Ray cluster address (e.g. 'auto' or 'ray://host:10001'); default: local")
    p.add_argument("--gym-packages", nargs="*", default=["envs"], help="modules that register the env")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> Path:
    args = parse_args(argv)
    preset = PRESETS[args.preset]
    epochs = args.epochs or preset["epochs"]
    k = args.learn_episodes or preset["learn_episodes"]
    m = args.test_episodes or preset["test_episodes"]
    seeds = args.seed_list if args.seed_list else list(range(args.seeds or preset["seeds"]))
    for package in args.gym_packages:
        importlib.import_module(package)
    gym_packages = list(args.gym_packages)
    out = Path(args.out or ROOT / "runs" / "reproduce" / args.env)

    hyperparams = {a: load_hyperparams(a, args.env, Path(args.hyperparams_dir)) for a in args.algos}
    if args.n_envs:
        for hp in hyperparams.values():
            hp["n_envs"] = args.n_envs
    config = {
        "env_id": args.env,
        "epochs": epochs,
        "learn_episodes": k,
        "test_episodes": m,
        "hyperparams": {a: {key: repr(v) for key, v in hp.items()} for a, hp in hyperparams.items()},
    }
    check_config(out, config)

    specs = [
        RunSpec(
            env_id=args.env,
            algo=a,
            seed=s,
            epochs=epochs,
            learn_episodes=k,
            test_episodes=m,
            hyperparams=hyperparams[a],
            out_dir=str(out),
            gym_packages=gym_packages,
            progress_file=str(out / "pairs" / f"{a}_seed{s}.progress"),
        )
        for a in args.algos
        for s in seeds
    ]
    todo = [s for s in specs if not pair_csv(out, s.algo, s.seed).exists()]
    skipped = len(specs) - len(todo)
    bar = None
    if not args.no_progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(specs) * epochs, initial=skipped * epochs, unit="epoch", desc=f"{args.env} grid")
    if skipped:
        print(f"resuming: {skipped} of {len(specs)} (algo, seed) runs already finished in {out}")
    try:
        run_grid(todo, backend=args.backend, workers=args.workers, ray_address=args.ray_address, bar=bar)
    finally:
        if bar is not None:
            bar.close()

    df = collect_results(out)
    df.to_csv(out / "results.csv", index=False)
    if not args.no_plots:
        from plots import make_figures, summary_table

        make_figures(df, out, title=f"{args.env}: K={k}, M={m}, {len(seeds)} seeds")
        (out / "summary.md").write_text(summary_table(df, env_id=args.env, k=k, m=m))
    print(f"results: {out / 'results.csv'} ({len(df)} rows)")
    return out


if __name__ == "__main__":
    main()
