"""How the temperature floor (``min_temperature``) changes learning: the README's floor table.

    python scripts/floor_sweep.py                     # CartPole-v1, floors 0.1 0.5 1 2, seeds 0-2
    python scripts/floor_sweep.py --env NomadOffice-v0 --floors 0.1 0.5 1 2 4 --seeds 0 1 2 3 4 5

CartPole-v1: 100k steps, 8 envs, A2C's defaults; the score is the mean return of 20
deterministic episodes (>= 400 solves it). NomadOffice-v0: 200k steps on the batched office with
16 robots and the zoo file's 2D settings (gamma 0.9, punishment gamma 0.1, ``n_steps=5``); the
score is the goal rate of the last 100 training episodes (>= 0.7: learned). "Above floor" is the
share of collected steps whose action was drawn at a temperature above the floor, i.e. where the
interest, not the floor, set the temperature. Each run is seeded; runs are spread over ``--workers`` processes.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from envs.nomad.batched import make_sb3_vec_env
from sb3_twodrl import NavigationMetricsCallback
from twodrl_bench.variants import VariantTwoDimA2C as TwoDimA2C  # the interest modes are variants

PAPER = dict(interest="paper", preferences="raw")
"""The floor study is of eq. 9 taken literally (the default interest is relative: README, "Design notes")."""

SETTINGS = {
    "CartPole-v1": dict(steps=100_000, threshold=400.0),
    "NomadOffice-v0": dict(steps=200_000, threshold=0.7),
}


class AboveFloor(BaseCallback):
    """Counts the collected steps whose action was drawn at a temperature above the floor."""

    def __init__(self, floor: float):
        super().__init__()
        self.floor, self.above, self.total = floor, 0, 0

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        inverse = self.model.rollout_buffer.inverse_temperatures  # 0 at episode starts (uniform)
        self.above += int(np.count_nonzero((inverse > 0) & (inverse < np.float32(1.0 / self.floor))))
        self.total += inverse.size


@dataclass(frozen=True)
class Run:
    env_id: str
    floor: float
    seed: int
    score: float
    above_floor: float


def run(env_id: str, floor: float, seed: int) -> Run:
    th.set_num_threads(1)
    above = AboveFloor(floor)
    if env_id == "CartPole-v1":
        env = make_vec_env(env_id, n_envs=8, seed=seed)
        model = TwoDimA2C("MlpPolicy", env, min_temperature=floor, seed=seed, **PAPER)
        model.learn(SETTINGS[env_id]["steps"], callback=above)
        score, _ = evaluate_policy(model, make_vec_env(env_id, n_envs=1, seed=seed + 100), n_eval_episodes=20)
    else:
        metrics = NavigationMetricsCallback(window=100)
        model = TwoDimA2C(
            "MlpPolicy",
            make_sb3_vec_env(16, seed=seed),
            gamma=0.9,
            punishment_gamma=0.1,
            reward_split="info",
            min_temperature=floor,
            seed=seed,
            **PAPER,
        )
        model.learn(SETTINGS[env_id]["steps"], callback=[above, metrics])
        score = metrics.metrics()["goal_rate"]
    return Run(env_id, floor, seed, float(score), above.above / above.total)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", choices=sorted(SETTINGS), default="CartPole-v1")
    parser.add_argument("--floors", type=float, nargs="+", default=[0.1, 0.5, 1.0, 2.0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    jobs = [(args.env, floor, seed) for floor in args.floors for seed in args.seeds]
    with ProcessPoolExecutor(args.workers) as pool:
        runs = list(pool.map(run, *zip(*jobs, strict=True)))
    threshold = SETTINGS[args.env]["threshold"]
    print(f"{args.env}, {SETTINGS[args.env]['steps']} steps, seeds {args.seeds}; score >= {threshold} counts")
    print("floor | scores | reached | steps above floor")
    digits = 0 if args.env == "CartPole-v1" else 2
    for floor in args.floors:
        mine = [r for r in runs if r.floor == floor]
        scores = ", ".join(f"{r.score:.{digits}f}" for r in mine)
        reached = sum(r.score >= threshold for r in mine)
        above = [100 * r.above_floor for r in mine]
        print(f"{floor:g} | {scores} | {reached}/{len(mine)} | {min(above):.1f}-{max(above):.1f}%")


if __name__ == "__main__":
    main()
