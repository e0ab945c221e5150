"""Time to learn an office against its shortest path: TwoDimA2C and A2C with the settings derived from the map.

For each map (generated offices by seed and size class, or map files), each algorithm trains with the packaged
``NomadOffice-v0`` hyperparameters and the settings :func:`twodrl_zoo.recipe.derive` derives
(exploring starts, discount, time limit, budget), on the batched env. Every ``--eval-every`` steps it runs 20
deterministic episodes from the map's start; it stops once learned (:class:`~sb3_twodrl.callbacks.GoalRecord`: a goal
rate >= :data:`~sb3_twodrl.callbacks.SUCCESS_THRESHOLD` in :data:`CHECKS_IN_A_ROW` checks) or at the budget. Printed
and written as CSV: shortest path, training seconds (wall and this process's CPU, one torch thread) and steps to
learn (evaluation time excluded), final goal rate.

    OMP_NUM_THREADS=1 python scripts/bench_offices.py --sizes S M L --seeds 1000 1001 --algos twoda2c a2c
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecEnv

import twodrl_envs  # noqa: F401  (registers the IDs)
from sb3_twodrl.callbacks import SUCCESS_THRESHOLD, GoalCheck, GoalRecord
from twodrl_bench.algorithms import make_model
from twodrl_bench.folders import append_row
from twodrl_bench.intervals import wilson
from twodrl_envs.nomad.core import office_core
from twodrl_zoo import hyperparams
from twodrl_zoo.evaluation import goal_rate, run_episodes
from twodrl_zoo.recipe import size_class
from twodrl_zoo.vec_env import make_test_env, make_train_env

ENV = "NomadOffice-v0"
TEST_EPISODES = 20
CHECKS_IN_A_ROW = 1
"""Checks in a row at the threshold that make a map learned: the one check the offices protocol registered
(``results/offices/preregistration.md``), not the train command's :data:`~sb3_twodrl.callbacks.PATIENCE`, so that the
committed rows are what this script makes."""


class LearnedStop(BaseCallback):
    """Every ``every`` steps, the goal rate of one deterministic episode from the map's start per test env
    (:func:`twodrl_zoo.evaluation.run_episodes`), a check of :attr:`record`; stops once the checks say the map is
    learned (:class:`~sb3_twodrl.callbacks.GoalRecord`, :data:`CHECKS_IN_A_ROW`), timing training apart from
    evaluation."""

    def __init__(self, test_env: VecEnv, every: int) -> None:
        super().__init__()
        self.test_env, self.every = test_env, every
        self.record = GoalRecord(SUCCESS_THRESHOLD, CHECKS_IN_A_ROW)
        self.train_s, self.train_cpu_s, self.rate, self.learned_steps = 0.0, 0.0, 0.0, -1
        self._next, self._since, self._cpu_since = every, 0.0, 0.0

    def _on_training_start(self) -> None:
        self._since, self._cpu_since = time.perf_counter(), time.process_time()

    def pause(self) -> None:
        """Add the time since the last resume to the training time."""
        self.train_s += time.perf_counter() - self._since
        self.train_cpu_s += time.process_time() - self._cpu_since

    def _on_step(self) -> bool:
        if self.num_timesteps < self._next:
            return True
        self._next += self.every
        self.pause()
        self.check()
        self._on_training_start()
        if self.record.learned:
            self.learned_steps = self.num_timesteps
            return False
        return True

    def check(self) -> None:
        """Run the test episodes: their goal rate (:attr:`rate`) is the record's next check."""
        self.rate = goal_rate(run_episodes(self.model, self.test_env))
        self.record.add(GoalCheck(self.num_timesteps, self.rate, float("nan")))


def run(algo: str, map_: str, seed: int, eval_every: int) -> dict[str, object]:
    facts = hyperparams.task_facts(ENV, {"map": map_})
    assert facts is not None, f"{map_}: the paper's maps derive no settings"
    hp = hyperparams.load(algo, ENV, env_kwargs={"map": map_})  # the packaged entry with the derived settings
    env = make_train_env(ENV, hp.n_envs, seed, "batched", hp.env_kwargs)
    test_env = make_test_env(ENV, TEST_EPISODES, "batched", hp.eval_env_kwargs)
    test_env.seed(seed)
    model = make_model(algo, env, {"policy": hp.policy, **hp.kwargs}, seed=seed, device="cpu")
    stop = LearnedStop(test_env, eval_every)
    model.learn(hp.n_timesteps, callback=stop)
    if stop.learned_steps < 0:  # the budget ran out between evaluations: one last one
        stop.pause()
        stop.check()
    return {
        "map": map_,
        "size": size_class(facts["shortest_path"]),
        "moves": facts["shortest_path"],
        "algo": algo,
        "seed": seed,
        "learned": stop.record.learned,
        "train_s": round(stop.train_s, 1),
        "train_cpu_s": round(stop.train_cpu_s, 1),
        "steps": stop.learned_steps if stop.learned_steps >= 0 else model.num_timesteps,
        "goal_rate": stop.rate,
        "budget": hp.n_timesteps,
    }


def table(rows: list[dict[str, str]]) -> str:
    """Markdown: per size and algorithm, maps learned (Wilson) and the training CPU time and steps of those that
    learned (median, largest); then every map, by shortest path."""
    lines = [
        "| size | algo | maps learned | 95% interval | CPU s to learn, median (max) | steps to learn, median (max) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for size in ("S", "M", "L", "XL"):
        for algo in sorted({r["algo"] for r in rows}, reverse=True):
            group = [r for r in rows if r["size"] == size and r["algo"] == algo]
            if not group:
                continue
            learned = [r for r in group if r["learned"] == "True"]
            low, high = wilson(len(learned), len(group))
            cpu = sorted(float(r["train_cpu_s"]) for r in learned)
            steps = sorted(int(r["steps"]) for r in learned)
            times = f"{np.median(cpu):.0f} ({cpu[-1]:.0f})" if cpu else "-"
            counts = f"{np.median(steps):,.0f} ({steps[-1]:,})" if steps else "-"
            lines.append(
                f"| {size} | {algo} | {len(learned)}/{len(group)} | [{low:.2f}, {high:.2f}] | {times} | {counts} |"
            )
    lines += [
        "",
        "| map | moves | algo | learned | CPU s | steps | goal rate | budget |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in sorted(rows, key=lambda r: (int(r["moves"]), r["map"], r["algo"])):
        lines.append(
            f"| {r['map']} | {r['moves']} | {r['algo']} | {r['learned']} | {r['train_cpu_s']} | {r['steps']} | "
            f"{float(r['goal_rate']):.2f} | {r['budget']} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="*", default=[], help="map files or names")
    parser.add_argument("--sizes", nargs="*", default=[], help="size classes of generated maps (S, M, L)")
    parser.add_argument("--map-seeds", nargs="*", type=int, default=[], help="generated map seeds")
    parser.add_argument("--algos", nargs="+", default=["twoda2c"], choices=["twoda2c", "a2c"])
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--eval-every", type=int, default=100_000)
    parser.add_argument("--out", type=Path, default=None, help="CSV to append rows to")
    parser.add_argument("--table", type=Path, default=None, help="print the markdown table of a rows CSV and exit")
    args = parser.parse_args()
    if args.table is not None:
        with args.table.open(newline="") as f:
            print(table(list(csv.DictReader(f))), end="")
        return
    th.set_num_threads(1)
    maps = list(args.maps) + [f"generated:{size}:{seed}" for size in args.sizes for seed in args.map_seeds]
    fields = [
        "map",
        "size",
        "moves",
        "algo",
        "seed",
        "learned",
        "train_s",
        "train_cpu_s",
        "steps",
        "goal_rate",
        "budget",
    ]
    print(" | ".join(fields))
    for map_ in maps:
        office_core(map_)  # a bad map fails before any training
        for algo in args.algos:
            row = run(algo, map_, args.seed, args.eval_every)
            print(" | ".join(str(row[f]) for f in fields), flush=True)
            if args.out is not None:
                append_row(args.out, tuple(fields), row)


if __name__ == "__main__":
    sys.exit(main())
