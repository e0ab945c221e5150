"""Training throughput of TwoDimA2C relative to A2C and of TwoDimPPO relative to PPO, measured side by side in one run.

    python scripts/bench_algo.py --env CartPole-v1 --n-envs 8 --steps 40000

Each pair trains on the same env id, n_envs, seed and stock arguments (the algorithms' defaults) in this
process (DummyVecEnv, one torch thread). A pair is named by its baseline, a name of the bench's table
(``twodrl_bench.algorithms.ALGOS``): ``a2c``/``ppo`` pair the 2D-RL algorithm with stock SB3 (what a user sees);
``a2c_fast``/``ppo_fast`` with the bench's stock arms, SB3's numbers on the same fast path as the 2D-RL
algorithms (``twodrl_bench.algorithms.baselines``): the cost of the 2D parts alone.
``--batched`` runs on the bench's batched envs (``twodrl_zoo.vec_env.make_train_env``) instead of DummyVecEnv.
Throughput is env steps per second of this process's CPU
time, so other load on a shared machine does not skew it; runs alternate (A2C, TwoDimA2C, PPO,
TwoDimPPO, A2C, ...) and the median of the repeats is reported.
"""

import argparse
import statistics
import time

import torch as th
from stable_baselines3.common.env_util import make_vec_env

import twodrl_envs  # noqa: F401  (registers the Nomad office ids)
from twodrl_bench.algorithms import algo_class, make_model
from twodrl_zoo.vec_env import make_train_env

PAIRS: dict[str, str] = {"a2c": "twoda2c", "ppo": "twodppo", "a2c_fast": "twoda2c", "ppo_fast": "twodppo"}
"""Each pair: its baseline's name, the measured algorithm's (names of ``twodrl_bench.algorithms.ALGOS``)."""
TARGET = 0.9


def steps_per_second(algo: str, env_id: str, n_envs: int, steps: int, seed: int, batched: bool) -> float:
    env = make_train_env(env_id, n_envs, seed) if batched else make_vec_env(env_id, n_envs=n_envs, seed=seed)
    model = make_model(algo, env, seed=seed, device="cpu")
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
    parser.add_argument("--pairs", nargs="+", choices=sorted(PAIRS), default=["a2c", "ppo", "a2c_fast", "ppo_fast"])
    parser.add_argument("--batched", action="store_true", help="the bench's batched envs instead of DummyVecEnv")
    args = parser.parse_args()
    th.set_num_threads(1)

    runs = {algo_class(algo).__name__: algo for pair in args.pairs for algo in (pair, PAIRS[pair])}
    rates: dict[str, list[float]] = {name: [] for name in runs}
    for _ in range(args.repeats):
        for name, algo in runs.items():
            rates[name].append(steps_per_second(algo, args.env, args.n_envs, args.steps, args.seed, args.batched))
    medians = {name: statistics.median(values) for name, values in rates.items()}
    print(f"env={args.env} n_envs={args.n_envs} steps={args.steps} seed={args.seed} repeats={args.repeats}")
    for name, values in rates.items():
        listed = ", ".join(f"{rate:.0f}" for rate in values)
        print(f"{name:26s} {medians[name]:10.0f} env steps per CPU second  (runs: {listed})")
    for pair in args.pairs:
        baseline, measured = (algo_class(algo).__name__ for algo in (pair, PAIRS[pair]))
        print(f"ratio {measured} / {baseline} = {medians[measured] / medians[baseline]:.3f}  (target >= {TARGET})")


if __name__ == "__main__":
    main()
