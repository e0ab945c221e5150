"""Environment speed, measured side by side in one run (targets: docs/speed.md).

* single-env ``NomadOffice-v0`` and ``NomadOfficeMemorable-v0`` steps/s divided by ``CartPole-v1``'s
  (target >= 0.5), all made with ``disable_env_checker=True`` and driven by the same loop,
  resetting when an episode ends, under two policies: uniformly random actions, and a
  collision-heavy one (random actions 0 and 1 only: north and east, so most Nomad episodes end at
  a wall within a few steps and resets weigh as they do early in learning);
* ``BatchedNomadOffice`` robot-steps/s at N = 1024 with sensor noise on (target >= 1,000,000);
* ``NomadOfficeReal-v0`` steps/s (continuous poses, ray cast every step).

    OMP_NUM_THREADS=1 python scripts/bench_env.py
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_envs.nomad.batched import BatchedNomadOffice


def single_env_rate(env_id: str, steps: int, seed: int = 0, n_actions: int | None = None) -> tuple[float, float]:
    """Steps per second of one env under random actions ``0..n_actions-1`` (all by default), resets
    included as training sees them; and the mean episode length."""
    env = gym.make(env_id, disable_env_checker=True)
    actions = np.random.default_rng(seed).integers(n_actions or env.action_space.n, size=steps).tolist()
    env.reset(seed=seed)
    episodes = 0
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            episodes += 1
            env.reset()
    return steps / (time.perf_counter() - start), steps / max(episodes, 1)


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
    for policy, n_actions in (("uniform", None), ("collision-heavy (actions 0, 1)", 2)):
        cartpole, cp_len = single_env_rate("CartPole-v1", args.steps, n_actions=n_actions)
        print(f"{policy} policy:")
        print(f"  {'CartPole-v1 steps/s':44s} {cartpole:12,.0f}   (mean episode {cp_len:.1f} steps)")
        for env_id in ("NomadOffice-v0", "NomadOfficeMemorable-v0"):
            rate, length = single_env_rate(f"twodrl_envs:{env_id}", args.steps, n_actions=n_actions)
            print(f"  {env_id + ' steps/s':44s} {rate:12,.0f}   (mean episode {length:.1f} steps)")
            print(f"  {env_id + ' / CartPole-v1 (>= 0.5)':44s} {rate / cartpole:12.2f}")
    real, _ = single_env_rate("twodrl_envs:NomadOfficeReal-v0", args.steps // 10)
    batched = batched_rate(args.n_envs, args.batched_steps)
    print(f"{f'batched N={args.n_envs} noisy robot-steps/s (>= 1e6)':46s} {batched:12,.0f}")
    print(f"{'NomadOfficeReal-v0 steps/s (uniform)':46s} {real:12,.0f}")


if __name__ == "__main__":
    main()
