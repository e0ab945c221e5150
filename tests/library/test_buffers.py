"""The two-stream buffer: each stream gets SB3's GAE with its own discounts, and stays aligned through ``get``."""

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.buffers import RolloutBuffer

from sb3_twodrl.common.buffers import TwoDimRolloutBuffer

N_STEPS, N_ENVS = 5, 3
OBS_SPACE, ACTION_SPACE = spaces.Box(-1, 1, (2,)), spaces.Discrete(2)


def random_streams(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "rewards": rng.normal(size=(N_STEPS, N_ENVS)).astype(np.float32),
        "punishments": rng.exponential(size=(N_STEPS, N_ENVS)).astype(np.float32),
        "values": rng.normal(size=(N_STEPS + 1, N_ENVS)).astype(np.float32),
        "punishment_values": rng.exponential(size=(N_STEPS + 1, N_ENVS)).astype(np.float32),
        "starts": rng.random((N_STEPS + 1, N_ENVS)) < 0.3,
    }


def sb3_buffer(rewards: np.ndarray, values: np.ndarray, starts: np.ndarray, gamma: float, lam: float) -> RolloutBuffer:
    buffer = RolloutBuffer(N_STEPS, OBS_SPACE, ACTION_SPACE, n_envs=N_ENVS, gamma=gamma, gae_lambda=lam)
    obs, actions, log_probs = np.zeros((N_ENVS, 2)), np.zeros(N_ENVS), th.zeros(N_ENVS)
    for t in range(N_STEPS):
        buffer.add(obs, actions, rewards[t], starts[t], th.tensor(values[t]), log_probs)
    buffer.compute_returns_and_advantage(th.tensor(values[-1]), starts[-1])
    return buffer


def two_dim_buffer(streams: dict[str, np.ndarray], **discounts: float) -> TwoDimRolloutBuffer:
    buffer = TwoDimRolloutBuffer(N_STEPS, OBS_SPACE, ACTION_SPACE, n_envs=N_ENVS, **discounts)
    for t in range(N_STEPS):
        buffer.add(
            np.zeros((N_ENVS, 2)),
            np.zeros(N_ENVS),
            streams["rewards"][t],
            streams["starts"][t],
            th.tensor(streams["values"][t]),
            th.zeros(N_ENVS),
            punishment=streams["punishments"][t],
            punishment_value=streams["punishment_values"][t],
            inverse_temperature=np.ones(N_ENVS, dtype=np.float32),
        )
    buffer.compute_returns_and_advantage(
        th.tensor(streams["values"][-1]), streams["starts"][-1], th.tensor(streams["punishment_values"][-1])
    )
    return buffer


def test_each_stream_gets_sb3_gae_with_its_own_discounts() -> None:
    streams = random_streams(0)
    buffer = two_dim_buffer(streams, gamma=0.9, gae_lambda=0.8, punishment_gamma=0.1, punishment_gae_lambda=0.5)
    reward = sb3_buffer(streams["rewards"], streams["values"], streams["starts"], 0.9, 0.8)
    punishment = sb3_buffer(streams["punishments"], streams["punishment_values"], streams["starts"], 0.1, 0.5)
    np.testing.assert_allclose(buffer.returns, reward.returns, rtol=1e-6)
    np.testing.assert_allclose(buffer.punishment_returns, punishment.returns, rtol=1e-6)
    np.testing.assert_allclose(buffer.advantages, reward.advantages - punishment.advantages, rtol=1e-5, atol=1e-6)


def test_punishment_arrays_stay_aligned_with_the_reward_arrays_through_get() -> None:
    streams = random_streams(1)
    streams["punishments"], streams["punishment_values"] = streams["rewards"], streams["values"]
    buffer = two_dim_buffer(streams, gamma=0.9, gae_lambda=0.8, punishment_gamma=0.9, punishment_gae_lambda=0.8)
    batch = next(buffer.get(batch_size=None))
    np.testing.assert_array_equal(batch.punishment_returns.numpy(), batch.returns.numpy())
    np.testing.assert_array_equal(buffer.punishment_values, buffer.values)
    np.testing.assert_array_equal(buffer.punishment_returns, buffer.returns)
