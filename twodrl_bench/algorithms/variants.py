"""The ablation's variants of 2D-RL (``docs/ablation.md``): what ``TwoDimA2C``/``TwoDimPPO`` do not do.

:class:`VariantTwoDimA2C` and :class:`VariantTwoDimPPO` take four more arguments, each a choice that
an ablation arm made (each arm of the spec ``ablation``, ``twodrl_bench/specs/ablation.yml``, sets them):

``interest`` (what sets ``T`` in eq. 9):

- ``"learned"``: the algorithms' own (:mod:`sb3_twodrl.common.interest`): ``T = I(s) / mean(delta+)``.
- ``"paper"``: ``T = delta+`` of the transition that led into the current state, clamped;
  an interest of exactly 0 (an episode's first step) means uniform actions. Eq. 9 literally.
  ``predict`` acts at a running estimate of the rollouts' mean interest (:data:`INTEREST_EMA_RATE`).
- ``"relative"``: ``T = delta+ / mean(delta+)``, that interest over its running mean; clamped, 0 as in ``"paper"``.

``preferences`` (what ``T`` divides, categorical actions only): ``"raw"`` (the actor's outputs,
eq. 9 literally) or ``"bounded"`` (the outputs divided by ``max(1, sd_a p(s, .) / preference_bound)``:
preferences whose spread over the actions is at most ``preference_bound``). A Gaussian's std is
multiplied by ``T`` in every mode.

``actor_update`` (the actor's score, which the utility multiplies): ``"compensated_skip_uniform"``
(the algorithms' own), ``"log_prob"`` (the untempered softmax's ``log pi(a|s)``; PPO: the ratio of
the raw preferences), ``"tempered"`` (``log pi_T(a|s)`` of the policy that drew the action),
``"compensated"`` (that, its gradient with the ``1/T`` taken out, also for uniform moves) or
``"preference"`` (eq. 10 literally: the taken action's preference ``p(s, a)``; ``VariantTwoDimA2C``
and ``Discrete`` actions only).

The variants also keep the punishment critic's orthogonal initialisation (gain 1), with which their
committed rows were made, so that those rows reproduce (the algorithms start ``V_P`` at 0). E.g. eq. 9 and eq. 10
as the paper writes them (the tabular oracle's setting)::

    VariantTwoDimA2C("MlpPolicy", env, interest="paper", actor_update="preference")
"""

from __future__ import annotations

import functools
from typing import Any, ClassVar

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.distributions import DiagGaussianDistribution, StateDependentNoiseDistribution
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.type_aliases import PyTorchObs, Schedule

from sb3_twodrl.a2c import TwoDimA2C
from sb3_twodrl.common.fast import build_optimizer
from sb3_twodrl.common.interest import relative_interest
from sb3_twodrl.common.policies import (
    TwoDimActorCriticCnnPolicy,
    TwoDimActorCriticPolicy,
    TwoDimMultiInputPolicy,
    TwoDimPolicyMixin,
    two_dim_policy_class,
)
from sb3_twodrl.common.utils import fast_mean
from sb3_twodrl.common.validation import check_positive
from sb3_twodrl.ppo import TwoDimPPO

INTEREST_MODES = ("paper", "relative", "learned")
PREFERENCE_MODES = ("raw", "bounded")
ACTOR_UPDATES = ("log_prob", "tempered", "compensated", "compensated_skip_uniform", "preference")
PREFERENCE_BOUND = 1.0
"""Default largest standard deviation over the actions of the ``"bounded"`` preferences."""
INTEREST_EMA_RATE = 0.1
"""Weight of the newest rollout's mean interest in the ``"paper"`` mode's running estimate used by ``predict``."""
VARIANT_ARGUMENTS = ("interest", "preferences", "preference_bound")
"""The variant policy's constructor arguments that the variant algorithms take as their own."""
_GAUSSIANS = (DiagGaussianDistribution, StateDependentNoiseDistribution)


def check_variant(interest: str, preferences: str, preference_bound: float) -> None:
    """Raise ``ValueError`` naming the argument unless the modes are of this module."""
    if interest not in INTEREST_MODES:
        raise ValueError(f"interest must be one of {INTEREST_MODES}, got {interest!r}")
    if preferences not in PREFERENCE_MODES:
        raise ValueError(f"preferences must be one of {PREFERENCE_MODES}, got {preferences!r}")
    check_positive("preference_bound", preference_bound)


def bounded_preferences(logits: th.Tensor, bound: float = PREFERENCE_BOUND) -> th.Tensor:
    """Preferences divided by ``max(1, sd over actions / bound)``: their spread is at most ``bound``."""
    spread = logits.std(dim=-1, unbiased=False, keepdim=True)
    return logits / th.clamp(spread / bound, min=1.0)


class VariantPolicyMixin(TwoDimPolicyMixin):
    """The 2D-RL policy with the ``interest`` and ``preferences`` modes of this module (constructor
    arguments, saved with the policy) and ``V_P``'s orthogonal initialisation, on the policy's extension
    points: ``_build`` (``V_P``'s initialisation; no ``I(s)`` head but in ``"learned"``, so that the
    rollout passes each transition's ``delta+``), :meth:`inverse_temperature`,
    :meth:`action_preferences` and :meth:`update_interest_scale`.

    The three arguments have no defaults in the policy: the variant algorithms always pass them, so a
    variant's file loaded by ``TwoDimA2C``/``TwoDimPPO`` (which do not) is refused by name.
    """

    def __init__(
        self,
        *args: Any,
        interest: str | None = None,
        preferences: str | None = None,
        preference_bound: float | None = None,
        **kwargs: Any,
    ):
        if interest is None or preferences is None or preference_bound is None:
            raise ValueError(
                f"{type(self).__name__} needs interest, preferences and preference_bound (got {interest!r}, "
                f"{preferences!r}, {preference_bound!r}): it is built by VariantTwoDimA2C or VariantTwoDimPPO; "
                "a file of theirs is loaded with their load"
            )
        check_variant(interest, preferences, preference_bound)
        self.interest = interest
        self.preferences = preferences
        self.preference_bound = preference_bound
        super().__init__(*args, **kwargs)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data.update({name: getattr(self, name) for name in VARIANT_ARGUMENTS})
        return data

    def _build(self, lr_schedule: Schedule) -> None:
        """``V_P`` orthogonally initialised (gain 1) as SB3's value head, from the same random state as the
        library's zero head (the arms' rows ran with it); no ``I(s)`` head but in ``"learned"``."""
        super()._build(lr_schedule)
        with th.random.fork_rng(devices=[]):
            self.punishment_value_net = self._new_head()
        if self.interest != "learned":
            self.interest_net = None
        self.optimizer = build_optimizer(self, lr_schedule)  # type: ignore[arg-type]

    def inverse_temperature(self, interest: np.ndarray) -> np.ndarray:
        """``"paper"``/``"relative"``: ``1 / T`` of the transition's ``delta+`` (relative: over its running
        mean), clamped; an interest of 0 gives uniform actions (a Gaussian: ``max_temperature``)."""
        if self.interest == "learned" or self.temperature != "interest":
            return super().inverse_temperature(interest)
        interest = np.asarray(interest, dtype=np.float32)
        if self.interest == "relative":
            interest = relative_interest(np.maximum(interest, 0.0), self.running_interest.item())
        inverse = np.reciprocal(np.minimum(np.maximum(interest, self.min_temperature), self.max_temperature))
        if isinstance(self.action_dist, _GAUSSIANS):
            inverse[interest == 0] = 1.0 / self.max_temperature
        else:
            inverse *= interest > 0
        return inverse

    def action_preferences(self, latent_pi: th.Tensor) -> th.Tensor:
        preferences = super().action_preferences(latent_pi)
        if self.preferences == "bounded":
            return bounded_preferences(preferences, self.preference_bound)
        return preferences

    def update_interest_scale(self, interest: np.ndarray, dones: np.ndarray) -> None:
        if self.interest != "paper":  # "paper" keeps a per-rollout estimate in the same buffer
            super().update_interest_scale(interest, dones)

    def update_rollout_interest(self, mean_interest: float) -> None:
        """``"paper"``: fold one rollout's mean interest into the estimate that ``predict`` uses."""
        if self.interest != "paper":
            return
        running = self.running_interest.item()
        self.running_interest.fill_(
            mean_interest if running == 0.0 else running + INTEREST_EMA_RATE * (mean_interest - running)
        )


class VariantActorCriticPolicy(VariantPolicyMixin, TwoDimActorCriticPolicy):
    """:class:`VariantPolicyMixin` on ``TwoDimActorCriticPolicy``."""


class VariantActorCriticCnnPolicy(VariantPolicyMixin, TwoDimActorCriticCnnPolicy):
    """:class:`VariantPolicyMixin` on ``TwoDimActorCriticCnnPolicy``."""


class VariantMultiInputPolicy(VariantPolicyMixin, TwoDimMultiInputPolicy):
    """:class:`VariantPolicyMixin` on ``TwoDimMultiInputPolicy``."""


@functools.cache
def variant_policy_class(policy_class: type) -> type[VariantPolicyMixin]:
    """:class:`VariantPolicyMixin` on a user's ``ActorCriticPolicy`` subclass (the class itself if it has it)."""
    if isinstance(policy_class, type) and issubclass(policy_class, VariantPolicyMixin):
        return policy_class
    base = two_dim_policy_class(policy_class)
    return type(f"Variant{base.__name__}", (VariantPolicyMixin, base), {"__module__": __name__})


def scored_actions(
    policy: VariantPolicyMixin, obs: PyTorchObs, actions: th.Tensor, inverse_temperature: th.Tensor, score: str
) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
    """``V_R``, ``V_P``, ``I(s)``, the ``actor_update`` score of ``actions`` and the entropy (eq. 10).

    ``"log_prob"``: log-probability and entropy under the raw preferences (``T = 1``);
    ``"tempered"``: under the tempered distribution that drew the actions (eq. 9);
    ``"compensated"``: the same with the ``1/T`` taken out of their gradient;
    ``"compensated_skip_uniform"``: the policy's own score; ``"preference"``: ``p(s, a)`` itself.
    """
    if score == "compensated_skip_uniform":
        return policy.evaluate_actions_two_dim(obs, actions, inverse_temperature)
    latent_pi, values, punishment_values, predicted = policy.evaluate_state(obs)
    if score in ("tempered", "compensated"):
        distribution = policy.tempered_distribution(latent_pi, inverse_temperature, score == "compensated")
    else:
        distribution = policy._get_action_dist_from_latent(latent_pi)
    if score == "preference":
        taken = policy.action_net(latent_pi).gather(1, actions.long().view(-1, 1)).flatten()
        return values, punishment_values, predicted, taken, distribution.entropy()
    return values, punishment_values, predicted, distribution.log_prob(actions), distribution.entropy()


class VariantMixin:
    """The variant arguments of an algorithm: stored, validated, passed to the policy, the score chosen
    (the algorithms' extension points ``_policy_two_dim_kwargs`` and ``_evaluate_actions``), and the
    ``"paper"`` mode's per-rollout estimate of the interest updated after each rollout."""

    actor_updates: ClassVar[tuple[str, ...]] = ACTOR_UPDATES
    policy: Any
    action_space: spaces.Space
    rollout_buffer: Any

    def __init__(
        self,
        policy: str | type,
        env: Any,
        *args: Any,
        interest: str = "learned",
        preferences: str = "raw",
        preference_bound: float = PREFERENCE_BOUND,
        actor_update: str = "compensated_skip_uniform",
        **kwargs: Any,
    ):
        check_variant(interest, preferences, preference_bound)
        if actor_update not in self.actor_updates:
            raise ValueError(f"actor_update must be one of {self.actor_updates}, got {actor_update!r}")
        self.interest = interest
        self.preferences = preferences
        self.preference_bound = preference_bound
        self.actor_update = actor_update
        super().__init__(policy if isinstance(policy, str) else variant_policy_class(policy), env, *args, **kwargs)
        if actor_update == "preference" and not isinstance(self.action_space, spaces.Discrete):
            raise ValueError(f"actor_update='preference' needs Discrete actions, got {self.action_space}")

    def _policy_two_dim_kwargs(self) -> dict[str, Any]:
        kwargs = super()._policy_two_dim_kwargs()  # type: ignore[misc]
        return {**kwargs, **{name: getattr(self, name) for name in VARIANT_ARGUMENTS}}

    def _evaluate_actions(
        self, observations: Any, actions: th.Tensor, inverse_temperatures: th.Tensor
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
        return scored_actions(self.policy, observations, actions, inverse_temperatures, self.actor_update)

    def collect_rollouts(self, *args: Any, **kwargs: Any) -> bool:
        """The algorithm's rollout; after a complete one, its mean interest goes to the ``"paper"`` estimate."""
        complete = super().collect_rollouts(*args, **kwargs)  # type: ignore[misc]
        if complete:
            self.policy.update_rollout_interest(fast_mean(self.rollout_buffer.interests))
        return complete


_VARIANT_POLICIES: dict[str, type[BasePolicy]] = {
    "MlpPolicy": VariantActorCriticPolicy,
    "CnnPolicy": VariantActorCriticCnnPolicy,
    "MultiInputPolicy": VariantMultiInputPolicy,
}


class VariantTwoDimA2C(VariantMixin, TwoDimA2C):
    """``TwoDimA2C`` with the ablation's ``interest``, ``preferences``, ``preference_bound`` and
    ``actor_update`` (module docstring); every other argument as ``TwoDimA2C``'s."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = _VARIANT_POLICIES


class VariantTwoDimPPO(VariantMixin, TwoDimPPO):
    """``TwoDimPPO`` with the ablation's ``interest``, ``preferences``, ``preference_bound`` and
    ``actor_update`` (not ``"preference"``: PPO clips a ratio of probabilities); with
    ``"log_prob"`` the ratio is the raw preferences' (``T = 1``)."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = _VARIANT_POLICIES
    actor_updates: ClassVar[tuple[str, ...]] = ("log_prob", "tempered", "compensated", "compensated_skip_uniform")

    def _rollout_log_prob(
        self, latent_pi: th.Tensor, actions: th.Tensor, log_prob: th.Tensor, inverse_temperature: np.ndarray
    ) -> th.Tensor:
        """``"log_prob"``: under the raw preferences (``T = 1``), the policy being optimised; ``"tempered"``
        and ``"compensated"``: the tempered ``log_prob``, also for a uniform draw, as they score it."""
        if self.actor_update == "log_prob":
            return self.policy._get_action_dist_from_latent(latent_pi).log_prob(actions)
        if self.actor_update in ("tempered", "compensated"):
            return log_prob
        return super()._rollout_log_prob(latent_pi, actions, log_prob, inverse_temperature)
