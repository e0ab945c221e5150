"""Exploratory diagnostic (docs/ablation.md, arm ``learned_skip_uniform``): the temperatures an interest mode
draws its actions at on CartPole-v1, at the slow learning check's settings.

``tests/test_learning.py``'s ``solves_cartpole`` (8 envs, 100k steps, SB3's A2C settings, 20 deterministic
evaluation episodes with seed + 100), with the temperature of every collected action recorded (episode
starts, drawn uniformly, excluded). Prints, per seed, the evaluation return and, for the first quarter,
the second quarter and the second half of training, the mean and 10/50/90% quantiles of ``T`` and the
shares of actions at the floor and at the ceiling.

    PYTHONPATH=. python docs/diagnostics/cartpole_temperatures.py relative '{"interest": "relative"}'
    PYTHONPATH=. python docs/diagnostics/cartpole_temperatures.py fixed1 '{"temperature": 1.0}' '[0, 1, 2]'
"""

import json
import sys

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from twodrl_bench.variants import VariantTwoDimA2C as TwoDimA2C  # the interest modes are variants


class InverseTemperatures(BaseCallback):
    """Keeps every rollout's ``1 / T`` per collected action."""

    def __init__(self) -> None:
        super().__init__()
        self.rollouts: list[np.ndarray] = []

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        self.rollouts.append(self.model.rollout_buffer.inverse_temperatures.ravel().copy())


def describe(inverse: np.ndarray, low: float, high: float) -> str:
    t = 1.0 / inverse[inverse > 0]
    q10, q50, q90 = np.quantile(t, (0.1, 0.5, 0.9))
    floor, ceiling = np.mean(t <= low + 1e-6), np.mean(t >= high - 1e-5)
    return f"T mean {t.mean():.2f} q10/50/90 {q10:.2f}/{q50:.2f}/{q90:.2f} floor {floor:.2f} ceil {ceiling:.3f}"


def main() -> None:
    th.set_num_threads(1)
    name, kwargs = sys.argv[1], json.loads(sys.argv[2])
    seeds = json.loads(sys.argv[3]) if len(sys.argv) > 3 else [0, 1, 2]
    for seed in seeds:
        record = InverseTemperatures()
        env = make_vec_env("CartPole-v1", n_envs=8, seed=seed)
        model = TwoDimA2C("MlpPolicy", env, seed=seed, **kwargs).learn(100_000, callback=record)
        mean_return, _ = evaluate_policy(
            model, make_vec_env("CartPole-v1", n_envs=1, seed=seed + 100), n_eval_episodes=20, deterministic=True
        )
        inverse = np.concatenate(record.rollouts)
        n = inverse.size
        parts = (inverse[: n // 4], inverse[n // 4 : n // 2], inverse[n // 2 :])
        text = " | ".join(describe(part, model.min_temperature, model.max_temperature) for part in parts)
        print(name, seed, f"return {mean_return:.1f}", text, flush=True)


if __name__ == "__main__":
    main()
