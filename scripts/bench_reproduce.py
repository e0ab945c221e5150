#!/usr/bin/env python
"""Throughput of the paper's protocol, both arms measured side by side in one run (targets: docs/speed.md).

For each n_envs: one (algo, seed) run per arm (``a2c`` is SB3's A2C on the experiments' fast path,
:mod:`twodrl_bench.algorithms.baselines`) of ``--epochs`` paper-sized epochs (K learning
trials, then M test trials, batched pipeline, exactly as :mod:`twodrl_bench.epochs` runs them; no
TensorBoard, checkpoints or models), timed by the process's CPU time (the machine is shared).
Prints learning env-steps per CPU second (target >= 100,000), TwoDimA2C / A2C (target >= 0.9),
the per-env pipeline of the old protocol (DummyVecEnv, ``--dummy-n-envs``) for comparison, and
the projected wall time of the paper preset (1000 epochs, 2 arms x 5 seeds) on ``--cores`` cores,
for the mean learning-episode length measured here and for episodes that all run to the time limit.

    OMP_NUM_THREADS=1 nice -n 10 python scripts/bench_reproduce.py --env NomadOffice-v0
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time

import gymnasium as gym
import torch as th

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_bench import Experiment, load_spec
from twodrl_bench.epochs import train

PAPER = "paper_preset/NomadOffice-v0"
"""The spec whose protocol the projection is for (1000 epochs of K = 1000, M = 100, 5 seeds)."""


def measure(env_id: str, algo: str, n_envs: int, vec_env: str, args: argparse.Namespace) -> dict[str, float]:
    protocol = {"epochs": args.epochs, "learn_episodes": args.learn_episodes, "test_episodes": args.test_episodes}
    protocol.update(vec_env=vec_env, checkpoint_every=0, save_model=False, tensorboard=False)
    spec = {"name": "bench_reproduce", "env": env_id, "protocol": protocol, "seeds": [args.seed], "report": "paper"}
    experiment = Experiment.from_spec({**spec, "arms": {algo: {"algo": algo, "override": {"n_envs": n_envs}}}})
    with tempfile.TemporaryDirectory() as out:
        (job,) = experiment.jobs(out)
        cpu, wall = time.process_time(), time.perf_counter()
        rows = train(job)
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    steps = rows[-1]["env_steps"]
    return {
        "steps": steps,
        "cpu_s": cpu,
        "wall_s": wall,
        "rate": steps / cpu,
        "length": steps / (args.epochs * args.learn_episodes),
    }


def main() -> None:
    paper = load_spec(PAPER)
    paper_protocol = paper["protocol"]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", default="NomadOffice-v0")
    p.add_argument("--n-envs", type=int, nargs="+", help="batched n_envs to measure (default: the YAML's)")
    p.add_argument("--dummy-n-envs", type=int, default=16, help="n_envs of the per-env comparison (0: skip)")
    p.add_argument("--epochs", type=int, default=3, help="epochs per measured run")
    p.add_argument("--learn-episodes", "-K", type=int, default=paper_protocol["learn_episodes"])
    p.add_argument("--test-episodes", "-M", type=int, default=paper_protocol["test_episodes"])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--cores", type=int, default=2, help="cores of the projection")
    p.add_argument("--repeats", type=int, default=1, help="runs per arm, alternating their order; the median rate")
    args = p.parse_args()
    arms = ("a2c", "twoda2c")
    default_n = int(Experiment.from_spec({**paper, "env": args.env}).arms["a2c"].hyperparams.get("n_envs", 1))
    configs = [("batched", n) for n in (args.n_envs or [default_n])]
    if args.dummy_n_envs:
        configs.append(("dummy", args.dummy_n_envs))
    th.optim.RMSprop([th.zeros(1, requires_grad=True)])  # the first optimizer imports torch._dynamo (seconds)
    runs: dict[tuple[str, int, str], list[dict[str, float]]] = {}
    for repeat in range(args.repeats):
        for vec_env, n in configs:
            for algo in arms if repeat % 2 == 0 else arms[::-1]:  # back to back, alternating the order
                runs.setdefault((vec_env, n, algo), []).append(r := measure(args.env, algo, n, vec_env, args))
                print(
                    f"{vec_env:8s} n_envs={n:5d} {algo:8s}: {r['steps']:9,d} steps in {r['cpu_s']:7.1f} CPU s "
                    f"({r['wall_s']:.1f} s wall): {r['rate']:9,.0f} env-steps/CPU s, mean episode {r['length']:.1f}",
                    flush=True,
                )
    # the runs of an arm are the same run (one seed), so only their rates differ
    results = {key: {**rs[0], "rate": statistics.median(r["rate"] for r in rs)} for key, rs in runs.items()}
    limit = gym.spec(args.env).max_episode_steps
    n_runs, epochs, k = 2 * len(paper["seeds"]), paper_protocol["epochs"], paper_protocol["learn_episodes"]
    print(f"\n{args.env}, {args.epochs} epochs of K={args.learn_episodes}, M={args.test_episodes}, seed {args.seed}")
    print(
        "| pipeline | n_envs | A2C env-steps/s | TwoDimA2C env-steps/s | TwoDimA2C / A2C | paper preset on "
        f"{args.cores} cores, measured episode length | ... every episode {limit} steps |"
    )
    print("|---|---|---|---|---|---|---|")
    for vec_env, n in configs:
        a, t = results[vec_env, n, "a2c"], results[vec_env, n, "twoda2c"]
        hours = []
        for length in (None, limit):
            cpu = sum(epochs * k * (length or r["length"]) / r["rate"] for r in (a, t)) * n_runs / 2
            hours.append(cpu / args.cores / 3600)
        print(
            f"| {vec_env} | {n} | {a['rate']:,.0f} | {t['rate']:,.0f} | {t['rate'] / a['rate']:.2f} | "
            f"{hours[0]:,.1f} h | {hours[1]:,.1f} h |"
        )


if __name__ == "__main__":
    main()
