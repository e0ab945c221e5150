"""The stock arms of the experiments: SB3's A2C and PPO with the same results, bit for bit, in less time.

:class:`FastActorCriticPolicy` computes SB3's action scores with the library's ``Categorical`` formulas
(:mod:`sb3_twodrl.common.fast`, the same operations with fewer Python calls) and a multi-tensor optimizer.
Neither changes a number: ``tests/bench/test_fast.py`` checks the parameters after learning against stock SB3's
bitwise. The 2D-RL algorithms have both already, so the two arms of a comparison run the same pipeline.
"""

from typing import ClassVar

import torch as th
from gymnasium import spaces
from stable_baselines3 import A2C, PPO
from stable_baselines3.common.policies import ActorCriticPolicy, BasePolicy
from stable_baselines3.common.type_aliases import PyTorchObs, Schedule
from torch import nn
from torch.nn import functional as F

from sb3_twodrl.common.fast import (
    build_optimizer,
    categorical_entropy,
    categorical_log_prob,
    categorical_sample,
    normalized,
)


class FastForwardMixin:
    """``forward`` and ``evaluate_actions`` of an ``ActorCriticPolicy`` with, for ``Discrete`` actions,
    ``Categorical``'s formulas on the tensors (:mod:`sb3_twodrl.common.fast`): SB3's results, bit for bit."""

    action_space: spaces.Space
    action_net: nn.Module
    value_net: nn.Module
    mlp_extractor: nn.Module
    share_features_extractor: bool

    def _categorical(self) -> bool:
        return isinstance(self.action_space, spaces.Discrete)

    def _latents(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
        """The actor's and the critic's latent features, as ``ActorCriticPolicy.forward`` computes them."""
        features = self.extract_features(obs)  # type: ignore[attr-defined]
        if self.share_features_extractor:
            return self.mlp_extractor(features)
        pi_features, vf_features = features
        return self.mlp_extractor.forward_actor(pi_features), self.mlp_extractor.forward_critic(vf_features)

    def forward(self, obs: th.Tensor, deterministic: bool = False) -> tuple[th.Tensor, th.Tensor, th.Tensor]:
        if not self._categorical():
            return super().forward(obs, deterministic)  # type: ignore[misc]
        latent_pi, latent_vf = self._latents(obs)
        values = self.value_net(latent_vf)
        log_probs = normalized(self.action_net(latent_pi))
        actions = th.argmax(F.softmax(log_probs, dim=-1), dim=1) if deterministic else categorical_sample(log_probs)
        return actions, values, categorical_log_prob(log_probs, actions)

    def evaluate_actions(self, obs: PyTorchObs, actions: th.Tensor) -> tuple[th.Tensor, th.Tensor, th.Tensor | None]:
        if not self._categorical():
            return super().evaluate_actions(obs, actions)  # type: ignore[misc]
        latent_pi, latent_vf = self._latents(obs)
        log_probs = normalized(self.action_net(latent_pi))
        values = self.value_net(latent_vf)
        return values, categorical_log_prob(log_probs, actions), categorical_entropy(log_probs)


class FastActorCriticPolicy(FastForwardMixin, ActorCriticPolicy):
    """SB3's ``ActorCriticPolicy`` (the ``MlpPolicy`` of A2C and PPO) with :class:`FastForwardMixin` and
    a multi-tensor optimizer (:func:`~sb3_twodrl.common.fast.build_optimizer`)."""

    def _build(self, lr_schedule: Schedule) -> None:
        super()._build(lr_schedule)
        self.optimizer = build_optimizer(self, lr_schedule)


class FastA2C(A2C):
    """SB3's ``A2C``; its ``MlpPolicy`` is :class:`FastActorCriticPolicy`."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {**A2C.policy_aliases, "MlpPolicy": FastActorCriticPolicy}


class FastPPO(PPO):
    """SB3's ``PPO``; its ``MlpPolicy`` is :class:`FastActorCriticPolicy`."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {**PPO.policy_aliases, "MlpPolicy": FastActorCriticPolicy}
