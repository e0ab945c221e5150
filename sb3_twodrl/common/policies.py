"""Actor-critic policies with a reward critic, a punishment critic and a tempered action distribution.

The actor keeps SB3's action network: its outputs are the preferences ``p(s, a)`` of eq. 9-10.
Actions are drawn from the softmax of ``p / T`` (eq. 9), ``T`` set by the interest ``delta+``
(eq. 2) in one of the modes of :mod:`sb3_twodrl.common.interest`, clamped to
``[min_temperature, max_temperature]``. :class:`TwoDimPolicyMixin` adds the punishment head and the tempered
distribution to any SB3 ``ActorCriticPolicy`` subclass
(:func:`two_dim_policy_class`); the temperature settings are the algorithm's arguments, handed
to the policy by :meth:`TwoDimPolicyMixin.set_temperature`.
"""

import functools
import math
from functools import partial
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.distributions import (
    DiagGaussianDistribution,
    Distribution,
    StateDependentNoiseDistribution,
)
from stable_baselines3.common.policies import ActorCriticPolicy, BaseModel
from stable_baselines3.common.torch_layers import CombinedExtractor, NatureCNN
from stable_baselines3.common.type_aliases import PyTorchObs
from torch import nn

from sb3_twodrl.common.interest import (
    PREFERENCE_BOUND,
    bounded_preferences,
    check_interest_modes,
    relative_interest,
    updated_scale,
)
from sb3_twodrl.common.validation import check_positive, is_real

INTEREST_EMA_RATE = 0.1
"""Weight of the newest rollout's mean interest in the ``"paper"`` mode's running estimate used by ``predict``."""

DEFAULT_TEMPERATURE: dict[str, Any] = dict(
    temperature="interest", min_temperature=0.5, max_temperature=10.0, interest="paper", preferences="raw"
)
"""The algorithms' default temperature settings, which a policy has until the algorithm sets its own."""

_GAUSSIANS = (DiagGaussianDistribution, StateDependentNoiseDistribution)

TEMPERED_SCORES = ("tempered", "compensated", "compensated_skip_uniform")
"""The scores of ``evaluate_actions_two_dim`` taken under the tempered distribution that drew the actions."""


def check_temperature(temperature: str | float, min_temperature: float, max_temperature: float) -> None:
    """Raise ``ValueError`` unless the temperature settings keep eq. 9 finite."""
    if isinstance(temperature, str):
        if temperature != "interest":
            raise ValueError(f'temperature must be "interest" or a positive float, got {temperature!r}')
    elif not (is_real(temperature) and math.isfinite(temperature) and temperature > 0):
        raise ValueError(f'temperature must be "interest" or a positive finite float, got {temperature!r}')
    if not (is_real(min_temperature) and math.isfinite(min_temperature) and min_temperature > 0):
        raise ValueError(f"min_temperature must be a positive finite float, got {min_temperature!r}")
    if not (is_real(max_temperature) and math.isfinite(max_temperature)):
        raise ValueError(f"max_temperature must be a finite float, got {max_temperature!r}")
    if min_temperature > max_temperature:
        raise ValueError(f"min_temperature ({min_temperature}) must not exceed max_temperature ({max_temperature})")


class TwoDimPolicyMixin:
    """
    Reward critic ``V_R`` (SB3's value head), punishment critic ``V_P`` (eq. 3-8) and the tempered
    distribution of eq. 9, on top of an SB3 ``ActorCriticPolicy``.

    ``V_P`` is a second linear head on SB3's critic network, beside ``V_R``'s: the two critics
    share the critic's hidden layers (not the actor's) and have their own loss weights (a
    separate network would cost a whole MLP pass per step; README, "Design notes"). The head is
    initialised without touching the global RNG, so that a seeded run draws the same random
    numbers as stock SB3.

    ``predict_values`` keeps SB3's meaning (``V_R``). ``evaluate_actions`` and ``forward`` use the
    raw preferences (``T = 1``); rollout collection and ``predict`` sample from the tempered
    distribution (eq. 9), ``predict`` with the running interest estimate saved with the policy
    (in the ``"learned"`` mode, with the interest head's estimate for the state).
    :meth:`add_interest_head` (the algorithm calls it in the ``"learned"`` mode) adds a third linear
    head ``I(s)`` on the critic network, fed a detached latent so that its loss does not flow into
    the critics' layers, and initialised without touching the global RNG.
    It relies only on what every ``ActorCriticPolicy`` has: ``mlp_extractor`` (``forward_actor``,
    ``forward_critic``, ``latent_dim_vf``), ``action_net``, ``value_net`` and ``action_dist``.
    """

    # ActorCriticPolicy's attributes that the mixin uses
    action_dist: Distribution
    action_net: nn.Module
    value_net: nn.Module
    mlp_extractor: Any
    log_std: th.Tensor
    ortho_init: bool
    share_features_extractor: bool
    pi_features_extractor: nn.Module
    vf_features_extractor: nn.Module
    running_interest: th.Tensor

    def __init__(self, *args: Any, **kwargs: Any):
        self.set_temperature(**DEFAULT_TEMPERATURE)
        self.interest_net: nn.Module | None = None
        super().__init__(*args, **kwargs)

    def set_temperature(
        self,
        temperature: str | float,
        min_temperature: float,
        max_temperature: float,
        interest: str = "paper",
        preferences: str = "raw",
        preference_bound: float = PREFERENCE_BOUND,
    ) -> None:
        """Set how the interest becomes the temperature of eq. 9 (the algorithm's arguments;
        ``interest``, ``preferences`` and ``preference_bound``: :mod:`sb3_twodrl.common.interest`)."""
        check_temperature(temperature, min_temperature, max_temperature)
        check_interest_modes(interest, preferences)
        check_positive("preference_bound", preference_bound)
        if temperature == "interest" and interest == "learned" and getattr(self, "interest_net", None) is None:
            raise ValueError('interest="learned" needs the interest head: call add_interest_head() first')
        self.temperature = temperature
        self.min_temperature = min_temperature
        self.max_temperature = max_temperature
        self.interest = interest
        self.preferences = preferences
        self.preference_bound = preference_bound

    def add_interest_head(self) -> None:
        """Add the ``"learned"`` mode's head ``I(s)`` (estimate of ``E[delta+ | s]``) and give it to the optimizer."""
        if self.interest_net is not None:
            return
        with th.random.fork_rng(devices=[]):
            self.interest_net = nn.Linear(self.mlp_extractor.latent_dim_vf, 1).to(self.device)  # type: ignore[attr-defined]
            if self.ortho_init:
                self.interest_net.apply(partial(self.init_weights, gain=1))  # type: ignore[attr-defined]
        self.optimizer.add_param_group({"params": list(self.interest_net.parameters())})  # type: ignore[attr-defined]

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)  # type: ignore[misc]
        with th.random.fork_rng(devices=[]):
            self.punishment_value_net = nn.Linear(self.mlp_extractor.latent_dim_vf, 1)
            if self.ortho_init:
                self.punishment_value_net.apply(partial(self.init_weights, gain=1))  # type: ignore[attr-defined]
        self.register_buffer("running_interest", th.zeros(()))  # type: ignore[attr-defined]
        self.optimizer = self.optimizer_class(  # type: ignore[attr-defined]
            self.parameters(),  # type: ignore[attr-defined]
            lr=lr_schedule(1),
            **self.optimizer_kwargs,  # type: ignore[attr-defined]
        )

    def evaluate_state(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor, th.Tensor, th.Tensor | None]:
        """Actor latent, ``V_R(s)``, ``V_P(s)`` and the interest head's ``I(s)`` (None without one) in one pass."""
        features = self.extract_features(obs)  # type: ignore[attr-defined]
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
        self,
        obs: PyTorchObs,
        actions: th.Tensor,
        score: str = "log_prob",
        inverse_temperature: th.Tensor | None = None,
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
        """``V_R``, ``V_P``, ``I(s)`` (None without a head), the actor's score of ``actions`` and the
        entropy (eq. 10): the score is the log-probability under the raw preferences (``T = 1``), with
        ``score="tempered"`` the log-probability and entropy under the tempered distribution the
        actions were drawn from (eq. 9, at ``inverse_temperature``), with ``score="compensated"`` the
        same values with the temperature's ``1/T`` taken out of their gradient, with
        ``score="compensated_skip_uniform"`` those values but 0 for the actions drawn uniformly
        (``1/T = 0``: the preferences played no part), or with ``score="preference"`` the preference
        ``p(s, a)`` itself (``Discrete`` actions)."""
        latent_pi, values, punishment_values, predicted = self.evaluate_state(obs)
        if score in TEMPERED_SCORES:
            if inverse_temperature is None:
                raise ValueError(f"score={score!r} needs the inverse temperatures the actions were drawn with")
            distribution = self.tempered_distribution(latent_pi, inverse_temperature, score != "tempered")
        else:
            distribution = self._get_action_dist_from_latent(latent_pi)  # type: ignore[attr-defined]
        if score == "preference":
            taken = self.action_net(latent_pi).gather(1, actions.long().view(-1, 1)).flatten()
            return values, punishment_values, predicted, taken, distribution.entropy()
        log_prob, entropy = distribution.log_prob(actions), distribution.entropy()
        if score == "compensated_skip_uniform":
            drawn = (th.as_tensor(inverse_temperature, device=log_prob.device).reshape(-1) > 0).to(log_prob.dtype)
            log_prob, entropy = log_prob * drawn, None if entropy is None else entropy * drawn
        return values, punishment_values, predicted, log_prob, entropy

    def predict_critics(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
        """Reward critic ``V_R(s)`` and punishment critic ``V_P(s)`` (eq. 3, 4)."""
        features = BaseModel.extract_features(self, obs, self.vf_features_extractor)  # type: ignore[arg-type]
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
        actions (``1/T = 0``), as the paper states; a Gaussian (gSDE's included) has no uniform
        limit and takes ``max_temperature`` instead.
        """
        if self.temperature != "interest":
            return np.full(np.shape(interest), 1.0 / self.temperature, dtype=np.float32)
        interest = np.asarray(interest, dtype=np.float32)
        if self.interest != "paper":
            interest = relative_interest(np.maximum(interest, 0.0), self.running_interest.item())
        inverse = np.reciprocal(np.minimum(np.maximum(interest, self.min_temperature), self.max_temperature))
        if self.interest == "learned":
            return inverse
        if isinstance(self.action_dist, _GAUSSIANS):
            inverse[interest == 0] = 1.0 / self.max_temperature
        else:
            inverse *= interest > 0
        return inverse

    def tempered_distribution(
        self, latent_pi: th.Tensor, inverse_temperature: np.ndarray | th.Tensor, compensated: bool = False
    ) -> Distribution:
        """Action distribution of eq. 9: preferences times ``1 / T``; a Gaussian's std (gSDE: its noise) times ``T``.

        gSDE's noise and std are linear in its latent features, so scaling the features by ``T``
        scales both (the exploration matrix is left as sampled). ``compensated``: the same
        distribution, but gradients reach the preferences as if they were the tempered ones
        (``d(p/T)/dp`` taken as 1), so any ``T * grad log pi_T`` is finite, also at ``1/T = 0``; a
        Gaussian's gradients hold no ``1/T`` (``T`` scales the std, whose log it shifts) and are unchanged.
        """
        inverse = th.as_tensor(inverse_temperature, device=latent_pi.device).reshape(-1, 1)
        mean_actions = self.action_net(latent_pi)
        if isinstance(self.action_dist, StateDependentNoiseDistribution):
            return self.action_dist.proba_distribution(mean_actions, self.log_std, latent_pi / inverse)
        if isinstance(self.action_dist, DiagGaussianDistribution):
            return self.action_dist.proba_distribution(mean_actions, self.log_std - th.log(inverse))
        if self.preferences == "bounded":
            mean_actions = bounded_preferences(mean_actions, self.preference_bound)
        if compensated:
            logits = mean_actions.detach() * inverse + (mean_actions - mean_actions.detach())
        else:
            logits = mean_actions * inverse
        return self.action_dist.proba_distribution(action_logits=logits)  # type: ignore[call-arg]

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
        features = BaseModel.extract_features(self, obs, self.pi_features_extractor)  # type: ignore[arg-type]
        return self.mlp_extractor.forward_actor(features)

    def _running_distribution(self, obs: PyTorchObs, latent_pi: th.Tensor) -> Distribution:
        if self.interest_net is None or self.interest != "learned":
            interest = np.full(len(latent_pi), self.running_interest.item(), dtype=np.float32)
        else:
            features = BaseModel.extract_features(self, obs, self.vf_features_extractor)  # type: ignore[arg-type]
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
            return self._get_action_dist_from_latent(latent_pi).get_actions(deterministic=True)  # type: ignore[attr-defined]
        return self._running_distribution(observation, latent_pi).get_actions()


class TwoDimActorCriticPolicy(TwoDimPolicyMixin, ActorCriticPolicy):
    """SB3's ``ActorCriticPolicy`` with the punishment critic and the tempered distribution (eq. 3-9)."""


class TwoDimActorCriticCnnPolicy(TwoDimActorCriticPolicy):
    """``TwoDimActorCriticPolicy`` with SB3's ``NatureCNN`` features extractor for images."""

    def __init__(self, *args: Any, features_extractor_class: type = NatureCNN, **kwargs: Any):
        super().__init__(*args, features_extractor_class=features_extractor_class, **kwargs)


class TwoDimMultiInputPolicy(TwoDimActorCriticPolicy):
    """``TwoDimActorCriticPolicy`` with SB3's ``CombinedExtractor`` for ``Dict`` observations."""

    def __init__(self, *args: Any, features_extractor_class: type = CombinedExtractor, **kwargs: Any):
        super().__init__(*args, features_extractor_class=features_extractor_class, **kwargs)


@functools.cache
def two_dim_policy_class(policy_class: type) -> type[TwoDimPolicyMixin]:
    """The 2D-RL version of an SB3 ``ActorCriticPolicy`` subclass (the class itself if it is one already).

    A user's subclass (custom ``mlp_extractor``, features extractor, ...) gets the punishment head
    and the tempered distribution by :class:`TwoDimPolicyMixin`; one class per ``policy_class``.

    :raises ValueError: if ``policy_class`` is not an ``ActorCriticPolicy`` subclass
    """
    if isinstance(policy_class, type) and issubclass(policy_class, TwoDimPolicyMixin):
        return policy_class
    if not (isinstance(policy_class, type) and issubclass(policy_class, ActorCriticPolicy)):
        raise ValueError(
            f"policy must be a subclass of stable_baselines3's ActorCriticPolicy, got {policy_class!r}: "
            "2D-RL adds its punishment critic head beside the ActorCriticPolicy's value head and tempers "
            "its action distribution (subclass ActorCriticPolicy or sb3_twodrl.TwoDimActorCriticPolicy)"
        )
    return type(f"TwoDim{policy_class.__name__}", (TwoDimPolicyMixin, policy_class), {"__module__": __name__})
