"""Moves per second of the MuJoCo stand-in robot beside the artifact model's, in one run (target: >= 500 for
``NomadOfficeMuJoCo-v0``, issue 60).

Both single envs are driven by the same loop under the same random actions, resetting when an episode ends.

    OMP_NUM_THREADS=1 python scripts/bench_mujoco.py
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import twodrl_envs  # noqa: F401  (registers the IDs)

IDS = ("NomadOfficeMuJoCo-v0", "NomadOfficeReal-v0")


def moves_per_second(env_id: str, moves: int, map_name: str | None, seed: int = 0) -> float:
    """Moves per second of one env under uniformly random actions, resets included."""
    env = gym.make(env_id, map=map_name, disable_env_checker=True)
    actions = np.random.default_rng(seed).integers(4, size=moves).tolist()
    env.reset(seed=seed)
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return moves / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--moves", type=int, default=3000, help="moves per env (default 3000)")
    parser.add_argument("--map", default=None, help="map of both envs (default: the paper's office)")
    args = parser.parse_args()
    rates = {env_id: moves_per_second(env_id, args.moves, args.map) for env_id in IDS}
    for env_id, rate in rates.items():
        print(f"{env_id:24s} {rate:8.0f} moves/s")
    print(f"ratio MuJoCo / Real         {rates[IDS[0]] / rates[IDS[1]]:8.2f}")


if __name__ == "__main__":
    main()
