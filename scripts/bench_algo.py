"""Training throughput of TwoDimA2C relative to stock A2C, measured side by side in one run.

    python scripts/bench_algo.py --env CartPole-v1 --n-envs 8 --steps 40000

Both algorithms train on the same env id, n_envs, seed and A2C arguments in this process
(DummyVecEnv, one torch thread). Throughput is env steps per second of this process's CPU
time, so other load on a shared machine does not skew it; runs alternate (A2C, TwoDimA2C,
A2C, ...) and the median of the repeats is reported.
"""

import argparse
import statistics
import time

import torch as th
from stable_baselines3 import A2C
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.env_util import make_vec_env

import envs  # noqa: F401  (registers the Nomad office ids)
from sb3_twodrl import TwoDimA2C


def steps_per_second(algo: type[BaseAlgorithm], env_id: str, n_envs: int, steps: int, seed: int) -> float:
    model = algo("MlpPolicy", make_vec_env(env_id, n_envs=n_envs, seed=seed), seed=seed, device="cpu")
    start = time.process_time()
    model.learn(steps)
    return model.num_timesteps / (time.process_time() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="CartPole-v1")
    parser.add_argument("--n-envs", type=int, default=8)
    parser.add_argument("--steps", type=int, default=40_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    th.set_num_threads(1)

    rates: dict[str, list[float]] = {"A2C": [], "TwoDimA2C": []}
    for _ in range(args.repeats):
        for algo in (A2C, TwoDimA2C):
            rates[algo.__name__].append(steps_per_second(algo, args.env, args.n_envs, args.steps, args.seed))
    a2c, twodim = (statistics.median(rates[name]) for name in ("A2C", "TwoDimA2C"))
    print(f"env={args.env} n_envs={args.n_envs} steps={args.steps} seed={args.seed} repeats={args.repeats}")
    for name, median in (("A2C", a2c), ("TwoDimA2C", twodim)):
        runs = ", ".join(f"{rate:.0f}" for rate in rates[name])
        print(f"{name:10s} {median:10.0f} env steps per CPU second  (runs: {runs})")
    print(f"ratio TwoDimA2C / A2C = {twodim / a2c:.3f}  (target >= 0.85)")


if __name__ == "__main__":
    main()
