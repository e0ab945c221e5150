"""Rollout buffers that keep the reward and the punishment stream apart (eq. 1-8)."""

from collections.abc import Generator
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import torch as th
from stable_baselines3.common.buffers import DictRolloutBuffer, RolloutBuffer
from stable_baselines3.common.type_aliases import PyTorchObs
from stable_baselines3.common.vec_env import VecNormalize


class TwoDimRolloutBufferSamples(NamedTuple):
    """SB3's rollout samples (``advantages`` being the utility) plus the punishment critic's old values and
    target, the interest ``delta+`` of each sample's transition (the interest head ``I(s)``'s target) and the
    inverse temperature its action was drawn with (eq. 9)."""

    observations: PyTorchObs
    actions: th.Tensor
    old_values: th.Tensor
    old_log_prob: th.Tensor
    advantages: th.Tensor
    returns: th.Tensor
    old_punishment_values: th.Tensor
    punishment_returns: th.Tensor
    interests: th.Tensor
    inverse_temperatures: th.Tensor


def td_errors_and_gae(
    rewards: np.ndarray,
    values: np.ndarray,
    episode_starts: np.ndarray,
    last_values: np.ndarray,
    dones: np.ndarray,
    gamma: np.ndarray,
    gamma_lambda: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """TD errors (eq. 7-8) and GAE(lambda) advantages of several streams at once.

    ``rewards`` and ``values`` are ``(n_steps, n_streams, n_envs)``, ``last_values``
    ``(n_streams, n_envs)``, ``episode_starts`` ``(n_steps, n_envs)``; ``gamma`` and
    ``gamma_lambda`` (``gamma * gae_lambda``) are float32 ``(n_streams, 1)``. Same float32
    arithmetic as SB3's ``RolloutBuffer.compute_returns_and_advantage``; with ``gae_lambda = 0``
    the advantages are the TD errors themselves.
    """
    next_values = np.concatenate([values[1:], last_values[None]])
    next_non_terminal = 1.0 - np.concatenate([episode_starts[1:], dones[None].astype(np.float32)])[:, None, :]
    deltas = rewards + gamma * next_values * next_non_terminal - values
    advantages = np.empty_like(rewards)  # every step is written below
    last_gae_lam = 0
    for step in reversed(range(len(rewards))):
        last_gae_lam = deltas[step] + gamma_lambda * next_non_terminal[step] * last_gae_lam
        advantages[step] = last_gae_lam
    return deltas, advantages


if TYPE_CHECKING:  # what the mixin extends, for the type checker; at run time it goes before that class
    _BufferBase = RolloutBuffer
else:
    _BufferBase = object


class TwoDimBufferMixin(_BufferBase):
    """Two-stream storage and advantage computation shared by the flat and the ``Dict`` buffer.

    Per step it stores ``r_P``, ``V_P`` and the inverse temperature used to act. After
    ``compute_returns_and_advantage``: ``advantages`` is the utility ``A_R - w * A_P`` (eq. 1 with
    GAE per stream), ``returns`` the reward critic's target, ``punishment_returns`` the punishment
    critic's, ``interests`` the per-step ``|delta_R| + |delta_P|`` (eq. 2) and ``utilities`` the
    per-step ``delta_R - delta_P`` (eq. 1).

    :param punishment_gamma: discount of the punishment stream (eq. 4)
    :param punishment_gae_lambda: GAE lambda of the punishment stream
    :param punishment_weight: weight ``w`` of the punishment advantage in the utility
    """

    def __init__(
        self,
        *args: Any,
        punishment_gamma: float = 0.1,
        punishment_gae_lambda: float = 1.0,
        punishment_weight: float = 1.0,
        **kwargs: Any,
    ):
        self.punishment_gamma = punishment_gamma
        self.punishment_gae_lambda = punishment_gae_lambda
        self.punishment_weight = punishment_weight
        super().__init__(*args, **kwargs)
        discounts = ((self.gamma, self.gae_lambda), (punishment_gamma, punishment_gae_lambda))
        self._gammas = np.array([[gamma] for gamma, _ in discounts], dtype=np.float32)
        self._gamma_lambdas = np.array([[gamma * lam] for gamma, lam in discounts], dtype=np.float32)

    def reset(self) -> None:
        super().reset()
        # Both streams side by side, so that their TD errors and GAE take one pass;
        # ``rewards``/``punishments`` and ``values``/``punishment_values`` are views into them
        shape = (self.buffer_size, 2, self.n_envs)
        self._evaluations = np.zeros(shape, dtype=np.float32)
        self._critic_values = np.zeros(shape, dtype=np.float32)
        self.rewards, self.punishments = self._evaluations[:, 0], self._evaluations[:, 1]
        self.values, self.punishment_values = self._critic_values[:, 0], self._critic_values[:, 1]
        self.punishment_returns = np.zeros((self.buffer_size, self.n_envs), dtype=np.float32)
        self.inverse_temperatures = np.zeros((self.buffer_size, self.n_envs), dtype=np.float32)
        self.interests = np.zeros((self.buffer_size, self.n_envs), dtype=np.float32)
        self.utilities = np.zeros((self.buffer_size, self.n_envs), dtype=np.float32)

    def add(  # type: ignore[override]  # SB3's add plus the 2D streams, which it must get
        self,
        *args: Any,
        punishment: np.ndarray,
        punishment_value: np.ndarray,
        inverse_temperature: np.ndarray,
        **kwargs: Any,
    ) -> None:
        """SB3's ``add`` plus ``r_P``, ``V_P(s)`` and the inverse temperature the action was drawn with."""
        self.punishments[self.pos] = punishment
        self.punishment_values[self.pos] = punishment_value
        self.inverse_temperatures[self.pos] = inverse_temperature
        super().add(*args, **kwargs)

    def compute_returns_and_advantage(  # type: ignore[override]  # plus the punishment critic's last values
        self, last_values: th.Tensor, dones: np.ndarray, last_punishment_values: th.Tensor
    ) -> None:
        """Per stream TD errors and GAE with its own gamma and lambda; the utility is the actor's advantage."""
        deltas, advantages = td_errors_and_gae(
            self._evaluations,
            self._critic_values,
            self.episode_starts,
            np.array([last_values.cpu().numpy().flatten(), last_punishment_values.cpu().numpy().flatten()]),
            dones,
            self._gammas,
            self._gamma_lambdas,
        )
        reward_deltas, punishment_deltas = deltas[:, 0], deltas[:, 1]
        reward_advantages, punishment_advantages = advantages[:, 0], advantages[:, 1]
        self.advantages = reward_advantages - self.punishment_weight * punishment_advantages
        self.returns = reward_advantages + self.values
        self.punishment_returns = punishment_advantages + self.punishment_values
        self.interests = np.abs(reward_deltas) + np.abs(punishment_deltas)
        self.utilities = reward_deltas - punishment_deltas

    def get(  # type: ignore[override]  # SB3's samples plus the 2D fields (a NamedTuple cannot extend SB3's)
        self, batch_size: int | None = None
    ) -> Generator[TwoDimRolloutBufferSamples, None, None]:
        if not self.generator_ready:  # flattened like SB3's arrays, so that they stay aligned with them
            for name in ("punishment_values", "punishment_returns", "interests", "inverse_temperatures"):
                setattr(self, name, self.swap_and_flatten(getattr(self, name)))
        for samples in super().get(batch_size):
            assert isinstance(samples, TwoDimRolloutBufferSamples)  # made by _get_samples below
            yield samples

    def _get_samples(  # type: ignore[override]  # as get
        self, batch_inds: np.ndarray, env: VecNormalize | None = None
    ) -> TwoDimRolloutBufferSamples:
        samples = super()._get_samples(batch_inds, env)
        to_torch = self.to_torch
        return TwoDimRolloutBufferSamples(
            observations=samples.observations,
            actions=samples.actions,
            old_values=samples.old_values,
            old_log_prob=samples.old_log_prob,
            advantages=samples.advantages,
            returns=samples.returns,
            old_punishment_values=to_torch(self.punishment_values[batch_inds].flatten()),
            punishment_returns=to_torch(self.punishment_returns[batch_inds].flatten()),
            interests=to_torch(self.interests[batch_inds].flatten()),
            inverse_temperatures=to_torch(self.inverse_temperatures[batch_inds].flatten()),
        )


class TwoDimRolloutBuffer(TwoDimBufferMixin, RolloutBuffer):
    """Two-stream rollout buffer for flat observations."""


class TwoDimDictRolloutBuffer(TwoDimBufferMixin, DictRolloutBuffer):  # type: ignore[misc]  # the overrides, as above
    """Two-stream rollout buffer for ``Dict`` observations."""
