"""Environment speed, measured side by side in one run (issue 4 targets).

* single-env ``NomadOffice-v0`` steps/s divided by ``CartPole-v1``'s (target >= 0.5); both made
  with ``disable_env_checker=True`` and driven by the same loop of uniformly random actions,
  resetting when an episode ends;
* ``BatchedNomadOffice`` robot-steps/s at N = 1024 with sensor noise on (target >= 1,000,000);
* ``NomadOfficeReal-v0`` steps/s (continuous poses, ray cast every step).

    OMP_NUM_THREADS=1 python scripts/bench_env.py
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import envs  # noqa: F401  (registers the IDs)
from envs.nomad.batched import BatchedNomadOffice


def single_env_rate(env_id: str, steps: int, seed: int = 0) -> float:
    """Steps per second of one env under random actions (resets included, as training sees them)."""
    env = gym.make(env_id, disable_env_checker=True)
    actions = np.random.default_rng(seed).integers(env.action_space.n, size=steps).tolist()
    env.reset(seed=seed)
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - start)


def batched_rate(n_envs: int, steps: int, seed: int = 0) -> float:
    """Robot-steps per second of the batched env with sensor noise on."""
    batched = BatchedNomadOffice(n_envs, sensor_noise=True)
    actions = np.random.default_rng(seed).integers(4, size=(steps, n_envs))
    batched.reset(seed=seed)
    start = time.perf_counter()
    for row in actions:
        batched.step(row)
    return steps * n_envs / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000, help="single-env steps per measurement")
    parser.add_argument("--batched-steps", type=int, default=500, help="batched steps (each moves N robots)")
    parser.add_argument("--n-envs", type=int, default=1024)
    args = parser.parse_args()
    cartpole = single_env_rate("CartPole-v1", args.steps)
    office = single_env_rate("envs:NomadOffice-v0", args.steps)
    real = single_env_rate("envs:NomadOfficeReal-v0", args.steps // 10)
    batched = batched_rate(args.n_envs, args.batched_steps)
    print(f"{'CartPole-v1 steps/s':42s} {cartpole:12,.0f}")
    print(f"{'NomadOffice-v0 steps/s':42s} {office:12,.0f}")
    print(f"{'NomadOffice-v0 / CartPole-v1 (>= 0.5)':42s} {office / cartpole:12.2f}")
    print(f"{f'batched N={args.n_envs} noisy robot-steps/s (>= 1e6)':42s} {batched:12,.0f}")
    print(f"{'NomadOfficeReal-v0 steps/s':42s} {real:12,.0f}")


if __name__ == "__main__":
    main()
