"""Time to learn an office against its shortest path: TwoDimA2C and A2C with the settings derived from the map.

For each map (generated offices by seed and size class, or map files), each algorithm trains with the packaged
``NomadOffice-v0`` hyperparameters and the settings :func:`twodrl_envs.nomad.settings.map_settings` derives
(exploring starts, discount, time limit, budget), on the batched env. Every ``--eval-every`` steps it runs 20
deterministic episodes from the map's start; it stops at a goal rate >= 0.8 (learned) or at the budget. Printed
and written as CSV: shortest path, training seconds and steps to learn (evaluation time excluded), final goal rate.

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
from stable_baselines3 import A2C
from stable_baselines3.common.callbacks import BaseCallback

import twodrl_envs  # noqa: F401  (registers the IDs)
from sb3_twodrl import TwoDimA2C, hyperparams
from twodrl_bench.vec_env import make_test_env, make_train_env
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.office import NomadOfficeEnv
from twodrl_envs.nomad.settings import map_settings

ALGOS = {"twoda2c": TwoDimA2C, "a2c": A2C}
ENV = "NomadOffice-v0"
TEST_EPISODES = 20


def goal_rate(model: A2C, test_env: object, steps: int) -> float:
    """Goal rate of ``TEST_EPISODES`` deterministic episodes from the map's start (one per test env)."""
    obs = test_env.reset()
    done_at = np.zeros(TEST_EPISODES, dtype=bool)
    success = np.zeros(TEST_EPISODES, dtype=bool)
    for _ in range(steps):
        actions, _ = model.predict(obs, deterministic=True)
        obs, _, dones, infos = test_env.step(actions)
        new = dones & ~done_at
        success[new] = [bool(infos[i].get("is_success")) for i in np.flatnonzero(new)]
        done_at |= dones
        if done_at.all():
            break
    return float(success.mean())


class LearnedStop(BaseCallback):
    """Evaluates every ``every`` steps; stops at a goal rate >= 0.8, timing training apart from evaluation."""

    def __init__(self, test_env: object, every: int, limit: int) -> None:
        super().__init__()
        self.test_env, self.every, self.limit = test_env, every, limit
        self.train_s, self.rate, self.learned_steps = 0.0, 0.0, -1
        self._next, self._since = every, 0.0

    def _on_training_start(self) -> None:
        self._since = time.perf_counter()

    def _on_step(self) -> bool:
        if self.num_timesteps < self._next:
            return True
        self._next += self.every
        self.train_s += time.perf_counter() - self._since
        self.rate = goal_rate(self.model, self.test_env, self.limit)
        self._since = time.perf_counter()
        if self.rate >= 0.8:
            self.learned_steps = self.num_timesteps
            return False
        return True


def run(algo: str, map_: str, seed: int, eval_every: int) -> dict[str, object]:
    settings = map_settings(NomadOfficeEnv(map_).robot)
    hp = hyperparams.load(algo, ENV)
    kwargs = dict(hp.kwargs)
    kwargs["gamma"] = settings.gamma
    env = make_train_env(ENV, hp.n_envs, seed, "batched", {"map": map_, **settings.env_kwargs()})
    test_env = make_test_env(ENV, TEST_EPISODES, "batched", {"map": map_, **settings.eval_env_kwargs()})
    test_env.seed(seed)
    model = ALGOS[algo](hp.policy, env, seed=seed, device="cpu", **kwargs)
    stop = LearnedStop(test_env, eval_every, settings.max_episode_steps)
    model.learn(settings.n_timesteps, callback=stop)
    if stop.learned_steps < 0:  # the budget ran out between evaluations: one last one
        stop.train_s += time.perf_counter() - stop._since
        stop.rate = goal_rate(model, test_env, settings.max_episode_steps)
    return {
        "map": map_,
        "size": settings.size,
        "moves": settings.shortest_path,
        "algo": algo,
        "seed": seed,
        "learned": stop.rate >= 0.8,
        "train_s": round(stop.train_s, 1),
        "steps": stop.learned_steps if stop.learned_steps >= 0 else model.num_timesteps,
        "goal_rate": stop.rate,
        "budget": settings.n_timesteps,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="*", default=[], help="map files or names")
    parser.add_argument("--sizes", nargs="*", default=[], help="size classes of generated maps (S, M, L)")
    parser.add_argument("--map-seeds", nargs="*", type=int, default=[], help="generated map seeds")
    parser.add_argument("--algos", nargs="+", default=["twoda2c"], choices=sorted(ALGOS))
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--eval-every", type=int, default=100_000)
    parser.add_argument("--out", type=Path, default=None, help="CSV to append rows to")
    args = parser.parse_args()
    th.set_num_threads(1)
    maps = list(args.maps) + [f"generated:{size}:{seed}" for size in args.sizes for seed in args.map_seeds]
    fields = ["map", "size", "moves", "algo", "seed", "learned", "train_s", "steps", "goal_rate", "budget"]
    print(" | ".join(fields))
    for map_ in maps:
        office_core(map_)  # a bad map fails before any training
        for algo in args.algos:
            row = run(algo, map_, args.seed, args.eval_every)
            print(" | ".join(str(row[f]) for f in fields), flush=True)
            if args.out is not None:
                new = not args.out.exists()
                with args.out.open("a", newline="") as f:
                    writer = csv.DictWriter(f, fieldnames=fields)
                    if new:
                        writer.writeheader()
                    writer.writerow(row)


if __name__ == "__main__":
    sys.exit(main())
