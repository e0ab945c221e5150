"""Actor-critic policy with a reward critic, a punishment critic and a tempered action distribution.

The actor keeps SB3's action network: its outputs are the preferences ``p(s, a)`` of eq. 9-10.
Actions are drawn from the softmax of ``p / T`` (eq. 9), ``T`` set by the interest ``delta+``
(eq. 2) in one of the modes of :mod:`sb3_twodrl.interest`, clamped to ``[min_temperature, max_temperature]``.
"""

from functools import partial
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.distributions import DiagGaussianDistribution, Distribution
from stable_baselines3.common.policies import ActorCriticPolicy, BaseModel
from stable_baselines3.common.torch_layers import CombinedExtractor, NatureCNN
from stable_baselines3.common.type_aliases import PyTorchObs
from torch import nn

from sb3_twodrl.interest import bounded_preferences, check_interest_settings, relative_interest, updated_scale

INTEREST_EMA_RATE = 0.1
"""Weight of the newest rollout's mean interest in the ``"paper"`` mode's running estimate used by ``predict``."""


class TwoDimActorCriticPolicy(ActorCriticPolicy):
    """
    Actor, reward critic ``V_R`` (SB3's value head) and punishment critic ``V_P`` (eq. 3-8).

    ``V_P`` is a second linear head on SB3's critic network, beside ``V_R``'s: the two critics
    share the critic's hidden layers (not the actor's) and have their own loss weights (a
    separate network would cost a whole MLP pass per step; README, "Design notes"). The head is
    initialised without touching the global RNG, so that a seeded run draws the same random
    numbers as stock A2C.

    ``predict_values`` keeps SB3's meaning (``V_R``). ``evaluate_actions`` and ``forward`` use the
    raw preferences (``T = 1``); rollout collection and ``predict`` sample from the tempered
    distribution (eq. 9), ``predict`` with the running interest estimate saved with the policy
    (in the ``"learned"`` mode, with the interest head's estimate for the state). The ``"learned"``
    mode adds a third linear head ``I(s)`` on the critic network, fed with a detached latent so
    that it does not change what the critics learn.

    :param temperature: ``"interest"`` (eq. 9, ``T`` set by the interest) or a fixed positive temperature
    :param interest: how the interest sets ``T``: ``"paper"``, ``"relative"`` or ``"learned"``
        (:mod:`sb3_twodrl.interest`)
    :param preferences: what ``T`` divides: ``"raw"`` or ``"bounded"`` preferences (:mod:`sb3_twodrl.interest`)
    :param min_temperature: floor of the interest temperature
    :param max_temperature: ceiling of the interest temperature
    :param args: positional arguments of ``ActorCriticPolicy``
    :param kwargs: keyword arguments of ``ActorCriticPolicy``
    """

    def __init__(
        self,
        *args: Any,
        temperature: str | float = "interest",
        interest: str = "paper",
        preferences: str = "raw",
        min_temperature: float = 0.5,
        max_temperature: float = 10.0,
        **kwargs: Any,
    ):
        check_interest_settings(temperature, interest, preferences, min_temperature, max_temperature)
        self.temperature = temperature
        self.interest = interest
        self.preferences = preferences
        self.min_temperature = min_temperature
        self.max_temperature = max_temperature
        super().__init__(*args, **kwargs)
        if self.use_sde:
            raise ValueError("use_sde=True is not supported: the temperature scales the Gaussian's own std")

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        with th.random.fork_rng(devices=[]):
            self.punishment_value_net = nn.Linear(self.mlp_extractor.latent_dim_vf, 1)
            if self.ortho_init:
                self.punishment_value_net.apply(partial(self.init_weights, gain=1))
            self.interest_net = nn.Linear(self.mlp_extractor.latent_dim_vf, 1) if self.interest == "learned" else None
            if self.interest_net is not None and self.ortho_init:
                self.interest_net.apply(partial(self.init_weights, gain=1))
        self.register_buffer("running_interest", th.zeros(()))
        self.optimizer = self.optimizer_class(self.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data.update(
            temperature=self.temperature,
            interest=self.interest,
            preferences=self.preferences,
            min_temperature=self.min_temperature,
            max_temperature=self.max_temperature,
        )
        return data

    def evaluate_state(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor, th.Tensor, th.Tensor | None]:
        """Actor latent, ``V_R(s)``, ``V_P(s)`` and the interest head's ``I(s)`` (None without one) in one pass."""
        features = self.extract_features(obs)
        if self.share_features_extractor:
            latent_pi, latent_vf = self.mlp_extractor(features)
        else:
            pi_features, vf_features = features
            latent_pi = self.mlp_extractor.forward_actor(pi_features)
            latent_vf = self.mlp_extractor.forward_critic(vf_features)
        return latent_pi, self.value_net(latent_vf), self.punishment_value_net(latent_vf), self._predicted(latent_vf)

    def _predicted(self, latent_vf: th.Tensor) -> th.Tensor | None:
        return None if self.interest_net is None else self.interest_net(latent_vf.detach())

    def evaluate_actions_two_dim(
        self, obs: PyTorchObs, actions: th.Tensor
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
        """``V_R``, ``V_P``, ``I(s)`` (None without a head), log-probability and entropy of ``actions``
        under the raw preferences (eq. 10)."""
        latent_pi, values, punishment_values, predicted = self.evaluate_state(obs)
        distribution = self._get_action_dist_from_latent(latent_pi)
        return values, punishment_values, predicted, distribution.log_prob(actions), distribution.entropy()

    def predict_critics(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
        """Reward critic ``V_R(s)`` and punishment critic ``V_P(s)`` (eq. 3, 4)."""
        features = BaseModel.extract_features(self, obs, self.vf_features_extractor)
        latent_vf = self.mlp_extractor.forward_critic(features)
        return self.value_net(latent_vf), self.punishment_value_net(latent_vf)

    def predict_punishment_values(self, obs: PyTorchObs) -> th.Tensor:
        """Punishment critic ``V_P(s)`` (eq. 4)."""
        return self.predict_critics(obs)[1]

    def inverse_temperature(self, interest: np.ndarray) -> np.ndarray:
        """``1 / T`` of eq. 9 for each interest value (float32): ``delta+`` of the transition into the
        state, or in the ``"learned"`` mode the head's ``I(s)``; divided by the running scale in the
        ``"relative"`` and ``"learned"`` modes.

        In the ``"paper"`` and ``"relative"`` modes an interest of exactly 0 gives uniform random
        actions (``1/T = 0``), as the paper states; a Gaussian has no uniform limit and takes
        ``max_temperature`` instead.
        """
        if self.temperature != "interest":
            return np.full(np.shape(interest), 1.0 / self.temperature, dtype=np.float32)
        interest = np.asarray(interest, dtype=np.float32)
        if self.interest != "paper":
            interest = relative_interest(np.maximum(interest, 0.0), self.running_interest.item())
        inverse = np.reciprocal(np.minimum(np.maximum(interest, self.min_temperature), self.max_temperature))
        if self.interest != "learned" and not isinstance(self.action_dist, DiagGaussianDistribution):
            inverse *= interest > 0
        return inverse

    def tempered_distribution(self, latent_pi: th.Tensor, inverse_temperature: np.ndarray) -> Distribution:
        """Action distribution of eq. 9: preferences times ``1 / T`` (a Gaussian's std times ``T``)."""
        inverse = th.from_numpy(inverse_temperature[:, None]).to(latent_pi.device)
        mean_actions = self.action_net(latent_pi)
        if isinstance(self.action_dist, DiagGaussianDistribution):
            return self.action_dist.proba_distribution(mean_actions, self.log_std - th.log(inverse))
        if self.preferences == "bounded":
            mean_actions = bounded_preferences(mean_actions)
        return self.action_dist.proba_distribution(action_logits=mean_actions * inverse)

    def update_interest_scale(self, interest: np.ndarray, dones: np.ndarray) -> None:
        """``"relative"``/``"learned"``: fold one vectorised step's interest into the running scale."""
        if self.interest != "paper":
            self.running_interest.fill_(updated_scale(self.running_interest.item(), interest, dones))

    def update_running_interest(self, mean_interest: float) -> None:
        """``"paper"``: fold one rollout's mean interest into the estimate that ``predict`` uses."""
        if self.interest != "paper":
            return
        running = self.running_interest.item()
        self.running_interest.fill_(
            mean_interest if running == 0.0 else running + INTEREST_EMA_RATE * (mean_interest - running)
        )

    def _actor_latent(self, obs: PyTorchObs) -> th.Tensor:
        return self.mlp_extractor.forward_actor(BaseModel.extract_features(self, obs, self.pi_features_extractor))

    def _running_distribution(self, obs: PyTorchObs, latent_pi: th.Tensor) -> Distribution:
        if self.interest_net is None:
            interest = np.full(len(latent_pi), self.running_interest.item(), dtype=np.float32)
        else:
            features = BaseModel.extract_features(self, obs, self.vf_features_extractor)
            predicted = self.interest_net(self.mlp_extractor.forward_critic(features))
            interest = predicted.detach().cpu().numpy().ravel()
        return self.tempered_distribution(latent_pi, self.inverse_temperature(interest))

    def get_distribution(self, obs: PyTorchObs) -> Distribution:
        """Tempered action distribution (eq. 9) at the running interest estimate (``"learned"``: at ``I(s)``)."""
        return self._running_distribution(obs, self._actor_latent(obs))

    def _predict(self, observation: PyTorchObs, deterministic: bool = False) -> th.Tensor:
        """Sample at the running interest, or take the argmax of the raw preferences if ``deterministic``."""
        latent_pi = self._actor_latent(observation)
        if deterministic:
            return self._get_action_dist_from_latent(latent_pi).get_actions(deterministic=True)
        return self._running_distribution(observation, latent_pi).get_actions()


class TwoDimActorCriticCnnPolicy(TwoDimActorCriticPolicy):
    """``TwoDimActorCriticPolicy`` with SB3's ``NatureCNN`` features extractor for images."""

    def __init__(self, *args: Any, features_extractor_class: type = NatureCNN, **kwargs: Any):
        super().__init__(*args, features_extractor_class=features_extractor_class, **kwargs)


class TwoDimMultiInputPolicy(TwoDimActorCriticPolicy):
    """``TwoDimActorCriticPolicy`` with SB3's ``CombinedExtractor`` for ``Dict`` observations."""

    def __init__(self, *args: Any, features_extractor_class: type = CombinedExtractor, **kwargs: Any):
        super().__init__(*args, features_extractor_class=features_extractor_class, **kwargs)
