"""Actor-critic policies with a reward critic, a punishment critic, an interest head and a tempered distribution.

The actor keeps SB3's action network: its outputs are the preferences ``p(s, a)`` of eq. 9-10.
Actions are drawn from the softmax of ``p / T`` (eq. 9). With ``temperature="interest"``, ``T`` is
set by the interest ``delta+`` (eq. 2) as :mod:`sb3_twodrl.common.interest` says: ``T = I(s) /
mean(delta+)``, ``I(s)`` a head of the critic network that estimates ``E[delta+ | s]``, clamped to
``[min_temperature, max_temperature]``; with a float, ``T`` is fixed. These are the policy's own
constructor arguments (saved with it, so that ``Policy.load`` rebuilds the same heads); the
algorithms pass theirs through. :class:`TwoDimPolicyMixin` adds all this to any SB3
``ActorCriticPolicy`` subclass (:func:`two_dim_policy_class`).
"""

import functools
import math
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np
import torch as th
from stable_baselines3.common.distributions import (
    CategoricalDistribution,
    DiagGaussianDistribution,
    Distribution,
    StateDependentNoiseDistribution,
)
from stable_baselines3.common.policies import ActorCriticPolicy, BaseModel
from stable_baselines3.common.torch_layers import CombinedExtractor, NatureCNN
from stable_baselines3.common.type_aliases import PyTorchObs
from torch import nn

from sb3_twodrl.common.fast import (
    build_optimizer,
    categorical_entropy,
    categorical_log_prob,
    categorical_sample,
    normalized,
)
from sb3_twodrl.common.interest import relative_interest, updated_scale
from sb3_twodrl.common.validation import is_real

_GAUSSIANS = (DiagGaussianDistribution, StateDependentNoiseDistribution)

TEMPERATURE_ARGUMENTS = ("temperature", "min_temperature", "max_temperature")
"""The policy's constructor arguments that the algorithms take as their own and pass through."""


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


if TYPE_CHECKING:  # what the mixin extends, for the type checker; at run time it goes before that class
    _PolicyBase = ActorCriticPolicy
else:
    _PolicyBase = object


class TwoDimPolicyMixin(_PolicyBase):
    """
    Reward critic ``V_R`` (SB3's value head), punishment critic ``V_P`` (eq. 3-8), interest head
    ``I(s)`` and the tempered distribution of eq. 9, on top of an SB3 ``ActorCriticPolicy``.

    ``V_P`` is a second linear head on SB3's critic network, beside ``V_R``'s: the two critics
    share the critic's hidden layers (not the actor's) and have their own loss weights (README,
    "Design notes"). It starts at exactly 0 (weights and bias 0): no punishment is expected before
    one is seen, so on an env without punishments ``A_P`` stays 0 and the utility is ``A_R`` (a
    randomly initialised ``V_P`` puts its own TD errors, noise, into the actor's advantage and the
    critics' shared layers). With ``temperature="interest"`` a third linear head ``I(s)`` on the
    critic network, fed a detached latent so that its loss does not flow into the critics' layers,
    estimates ``E[delta+ | s]``. The heads are built without touching the global RNG, so that a
    seeded run draws the same random numbers as stock SB3.

    ``predict_values`` keeps SB3's meaning (``V_R``). ``evaluate_actions`` and ``forward`` use the
    raw preferences (``T = 1``); rollout collection and ``predict`` sample from the tempered
    distribution (eq. 9), ``predict`` at the interest head's estimate for the state.
    It relies only on what every ``ActorCriticPolicy`` has: ``mlp_extractor`` (``forward_actor``,
    ``forward_critic``, ``latent_dim_vf``), ``action_net``, ``value_net`` and ``action_dist``.

    Extension points (``docs/design.md``, "Extension points"), each a method a subclass overrides,
    as SB3's policies are extended through ``_build`` and ``_get_action_dist_from_latent``:

    - :meth:`action_preferences`: the preferences ``p(s, .)`` that ``T`` divides (eq. 9).
    - :meth:`inverse_temperature`: ``1 / T`` from an interest; a value of 0 draws the action uniformly,
      and such an action scores 0 in the actor's update (:meth:`evaluate_actions_two_dim`).
    - :meth:`update_interest_scale`: what each rollout step's interest updates (``running_interest``).
    - ``interest_net``: a subclass whose ``_build`` leaves it None gets, during rollouts, each
      transition's ``delta+`` into the state (eq. 9 as written; 0 after a reset) as the interest,
      and ``predict`` gets ``running_interest``; with the head, both get its ``I(s)``.

    :param temperature: ``"interest"`` (eq. 9, ``T`` set by the interest) or a fixed positive temperature
    :param min_temperature: floor of the interest temperature
    :param max_temperature: ceiling of the interest temperature
    """

    running_interest: th.Tensor

    def __init__(
        self,
        *args: Any,
        temperature: str | float = "interest",
        min_temperature: float = 0.5,
        max_temperature: float = 10.0,
        **kwargs: Any,
    ):
        check_temperature(temperature, min_temperature, max_temperature)
        self.temperature = temperature
        self.min_temperature = min_temperature
        self.max_temperature = max_temperature
        super().__init__(*args, **kwargs)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data.update({name: getattr(self, name) for name in TEMPERATURE_ARGUMENTS})
        return data

    def _new_head(self) -> nn.Linear:
        """A linear head on the critic's latent, orthogonally initialised (gain 1) as SB3's value head."""
        head = nn.Linear(self.mlp_extractor.latent_dim_vf, 1)
        if self.ortho_init:
            head.apply(partial(self.init_weights, gain=1))
        return head

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        with th.random.fork_rng(devices=[]):
            self.punishment_value_net = self._new_head()
        nn.init.zeros_(self.punishment_value_net.weight)  # no punishment expected before one is seen
        nn.init.zeros_(self.punishment_value_net.bias)
        self.interest_net: nn.Module | None = None
        if self.temperature == "interest":
            with th.random.fork_rng(devices=[]):
                self.interest_net = self._new_head()
        self.register_buffer("running_interest", th.zeros(()))
        self.optimizer = build_optimizer(self, lr_schedule)

    def evaluate_state(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor, th.Tensor, th.Tensor | None]:
        """Actor latent, ``V_R(s)``, ``V_P(s)`` and the interest head's ``I(s)`` (None without one) in one pass."""
        latent_pi, latent_vf = self._latents(obs)
        values, punishment_values = self.value_net(latent_vf), self.punishment_value_net(latent_vf)
        return latent_pi, values, punishment_values, self._predicted(latent_vf)

    def _latents(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
        """The actor's and the critic's latent features, as ``ActorCriticPolicy.forward`` computes them."""
        features = self.extract_features(obs)
        if self.share_features_extractor:
            return self.mlp_extractor(features)
        pi_features, vf_features = features
        return self.mlp_extractor.forward_actor(pi_features), self.mlp_extractor.forward_critic(vf_features)

    def _predicted(self, latent_vf: th.Tensor) -> th.Tensor | None:
        return None if self.interest_net is None else self.interest_net(latent_vf.detach())

    def evaluate_actions_two_dim(
        self, obs: PyTorchObs, actions: th.Tensor, inverse_temperature: th.Tensor
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
        """``V_R``, ``V_P``, ``I(s)`` (None without a head), the actor's score of ``actions`` and the entropy.

        The score is the log-probability under the tempered distribution that drew each action
        (eq. 9, at its ``inverse_temperature``) with the ``1/T`` taken out of its gradient, so that
        ``A * score`` moves the preferences by ``A * (1[a] - pi_T(.|s))`` at any ``T`` (eq. 10 as a
        policy gradient of the policy that acted); the entropy likewise. An action drawn uniformly
        (``1/T = 0``) scores 0: the preferences played no part in it.
        """
        latent_pi, values, punishment_values, predicted = self.evaluate_state(obs)
        entropy: th.Tensor | None
        if self._categorical():
            log_probs = normalized(self._tempered_logits(latent_pi, inverse_temperature, compensated=True))
            log_prob, entropy = categorical_log_prob(log_probs, actions), categorical_entropy(log_probs)
        else:
            distribution = self.tempered_distribution(latent_pi, inverse_temperature, compensated=True)
            log_prob, entropy = distribution.log_prob(actions), distribution.entropy()
        drawn = (th.as_tensor(inverse_temperature, device=log_prob.device).reshape(-1) > 0).to(log_prob.dtype)
        return values, punishment_values, predicted, log_prob * drawn, None if entropy is None else entropy * drawn

    def predict_critics(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
        """Reward critic ``V_R(s)`` and punishment critic ``V_P(s)`` (eq. 3, 4)."""
        features = BaseModel.extract_features(self, obs, self.vf_features_extractor)
        latent_vf = self.mlp_extractor.forward_critic(features)
        return self.value_net(latent_vf), self.punishment_value_net(latent_vf)

    def predict_punishment_values(self, obs: PyTorchObs) -> th.Tensor:
        """Punishment critic ``V_P(s)`` (eq. 4)."""
        return self.predict_critics(obs)[1]

    def inverse_temperature(self, interest: np.ndarray) -> np.ndarray:
        """``1 / T`` of eq. 9 for each interest value (float32): at ``temperature="interest"`` the head's
        ``I(s)`` over the running mean of ``delta+`` (:func:`~sb3_twodrl.common.interest.relative_interest`),
        clamped to ``[min_temperature, max_temperature]``; otherwise ``1 / temperature``."""
        if not isinstance(self.temperature, str):  # a fixed temperature (the only string is "interest")
            return np.full(np.shape(interest), 1.0 / self.temperature, dtype=np.float32)
        interest = np.asarray(interest, dtype=np.float32)
        interest = relative_interest(np.maximum(interest, 0.0), self.running_interest.item())
        return np.reciprocal(np.minimum(np.maximum(interest, self.min_temperature), self.max_temperature))

    def action_preferences(self, latent_pi: th.Tensor) -> th.Tensor:
        """The preferences ``p(s, .)`` that ``T`` divides in eq. 9 (categorical actions): the action net's outputs."""
        return self.action_net(latent_pi)

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
        if not isinstance(self.action_dist, _GAUSSIANS):
            logits = self._tempered_logits(latent_pi, inverse_temperature, compensated)
            return self.action_dist.proba_distribution(action_logits=logits)
        inverse = th.as_tensor(inverse_temperature, device=latent_pi.device).reshape(-1, 1)
        mean_actions = self.action_net(latent_pi)
        if isinstance(self.action_dist, StateDependentNoiseDistribution):
            return self.action_dist.proba_distribution(mean_actions, self.log_std, latent_pi / inverse)
        return self.action_dist.proba_distribution(mean_actions, self.log_std - th.log(inverse))

    def _tempered_logits(
        self, latent_pi: th.Tensor, inverse_temperature: np.ndarray | th.Tensor, compensated: bool = False
    ) -> th.Tensor:
        """The preferences times ``1 / T`` (eq. 9) of a categorical policy (see :meth:`tempered_distribution`)."""
        inverse = th.as_tensor(inverse_temperature, device=latent_pi.device).reshape(-1, 1)
        preferences = self.action_preferences(latent_pi)
        if compensated:
            return preferences.detach() * inverse + (preferences - preferences.detach())
        return preferences * inverse

    def sample_tempered(
        self, latent_pi: th.Tensor, inverse_temperature: np.ndarray | th.Tensor
    ) -> tuple[th.Tensor, th.Tensor]:
        """Actions drawn from the tempered distribution (eq. 9) and their log-probabilities under it
        (``tempered_distribution(...).get_actions()`` and ``log_prob``, the same numbers)."""
        if self._categorical():
            log_probs = normalized(self._tempered_logits(latent_pi, inverse_temperature))
            actions = categorical_sample(log_probs)
            return actions, categorical_log_prob(log_probs, actions)
        distribution = self.tempered_distribution(latent_pi, inverse_temperature)
        actions = distribution.get_actions()
        return actions, distribution.log_prob(actions)

    def _categorical(self) -> bool:
        return isinstance(self.action_dist, CategoricalDistribution)

    def update_interest_scale(self, interest: np.ndarray, dones: np.ndarray) -> None:
        """Fold one vectorised step's interest into the running mean of ``delta+`` that scales ``I(s)``."""
        self.running_interest.fill_(updated_scale(self.running_interest.item(), interest, dones))

    def _actor_latent(self, obs: PyTorchObs) -> th.Tensor:
        features = BaseModel.extract_features(self, obs, self.pi_features_extractor)
        return self.mlp_extractor.forward_actor(features)

    def _running_inverse_temperature(self, obs: PyTorchObs, latent_pi: th.Tensor) -> np.ndarray:
        if self.interest_net is None:
            interest = np.full(len(latent_pi), self.running_interest.item(), dtype=np.float32)
        else:
            features = BaseModel.extract_features(self, obs, self.vf_features_extractor)
            predicted = self.interest_net(self.mlp_extractor.forward_critic(features))
            interest = predicted.detach().cpu().numpy().ravel()
        return self.inverse_temperature(interest)

    def get_distribution(self, obs: PyTorchObs) -> Distribution:
        """Tempered action distribution (eq. 9) at the interest head's ``I(s)`` (or the fixed temperature)."""
        latent_pi = self._actor_latent(obs)
        return self.tempered_distribution(latent_pi, self._running_inverse_temperature(obs, latent_pi))

    def _predict(self, observation: PyTorchObs, deterministic: bool = False) -> th.Tensor:
        """Sample from the tempered distribution, or take the argmax of the raw preferences if ``deterministic``."""
        latent_pi = self._actor_latent(observation)
        if deterministic:
            return self._get_action_dist_from_latent(latent_pi).get_actions(deterministic=True)
        return self.sample_tempered(latent_pi, self._running_inverse_temperature(observation, latent_pi))[0]


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
