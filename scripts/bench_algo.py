"""Training throughput of TwoDimA2C relative to A2C and of TwoDimPPO relative to PPO, measured side by side in one run.

    python scripts/bench_algo.py --env CartPole-v1 --n-envs 8 --steps 40000

Each pair trains on the same env id, n_envs, seed and stock arguments (the algorithms' defaults) in this
process (DummyVecEnv, one torch thread). ``a2c``/``ppo`` pair the 2D-RL algorithm with stock SB3 (what
a user sees); ``a2c-fast``/``ppo-fast`` with the bench's stock arms, SB3's numbers on the same fast
path as the 2D-RL algorithms (``twodrl_bench.baselines``): the cost of the 2D parts alone.
Throughput is env steps per second of this process's CPU
time, so other load on a shared machine does not skew it; runs alternate (A2C, TwoDimA2C, PPO,
TwoDimPPO, A2C, ...) and the median of the repeats is reported.
"""

import argparse
import statistics
import time

import torch as th
from stable_baselines3 import A2C, PPO
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.env_util import make_vec_env

import envs  # noqa: F401  (registers the Nomad office ids)
from sb3_twodrl import TwoDimA2C, TwoDimPPO
from twodrl_bench.baselines import BatchedA2C, BatchedPPO

PAIRS: dict[str, tuple[type[BaseAlgorithm], type[BaseAlgorithm]]] = {
    "a2c": (A2C, TwoDimA2C),
    "ppo": (PPO, TwoDimPPO),
    "a2c-fast": (BatchedA2C, TwoDimA2C),
    "ppo-fast": (BatchedPPO, TwoDimPPO),
}
TARGET = 0.9


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
    parser.add_argument("--pairs", nargs="+", choices=sorted(PAIRS), default=["a2c", "ppo", "a2c-fast", "ppo-fast"])
    args = parser.parse_args()
    th.set_num_threads(1)

    algos = list(dict.fromkeys(algo for pair in args.pairs for algo in PAIRS[pair]))
    rates: dict[str, list[float]] = {algo.__name__: [] for algo in algos}
    for _ in range(args.repeats):
        for algo in algos:
            rates[algo.__name__].append(steps_per_second(algo, args.env, args.n_envs, args.steps, args.seed))
    medians = {name: statistics.median(runs) for name, runs in rates.items()}
    print(f"env={args.env} n_envs={args.n_envs} steps={args.steps} seed={args.seed} repeats={args.repeats}")
    for name, runs in rates.items():
        listed = ", ".join(f"{rate:.0f}" for rate in runs)
        print(f"{name:10s} {medians[name]:10.0f} env steps per CPU second  (runs: {listed})")
    for pair in args.pairs:
        stock, two_dim = (algo.__name__ for algo in PAIRS[pair])
        print(f"ratio {two_dim} / {stock} = {medians[two_dim] / medians[stock]:.3f}  (target >= {TARGET})")


if __name__ == "__main__":
    main()
