"""The bench's self-tuning entropy arms: A2C, PPO, TwoDimA2C and TwoDimPPO with SAC's ``ent_coef="auto"``.

Stock A2C and PPO add ``ent_coef * H(pi(.|s))`` to their objective at a coefficient set by hand. SAC
(Haarnoja et al. 2018, "Soft Actor-Critic Algorithms and Applications", section 5) learns it instead:
the coefficient ``alpha`` is a Lagrange multiplier of the constraint ``H >= H_target``, one gradient step
on ``log alpha`` per gradient step of the algorithm, on the loss ``-log(alpha) * (H_target - H)`` averaged
over the batch (SB3's ``sac/sac.py`` with ``ent_coef="auto"``; for discrete actions the exact entropy of
each state's distribution, Christodoulou 2019, "Soft Actor-Critic for Discrete Action Settings",
arXiv:1910.07207). So alpha grows while the policy's entropy is below the target and shrinks while above.

The target is a fraction of the action space's maximum entropy (:func:`max_entropy`): ``log |A|`` for
``Discrete``, ``sum(log n_i)`` for ``MultiDiscrete`` (SB3's distribution is a product of independent
categoricals, its entropy the sum), ``n log 2`` for ``MultiBinary``. ``Box`` is refused: a Gaussian's
entropy has no maximum, so no fraction of it is a target (SAC's ``-dim(A)`` is not offered here).

As in SAC, the coefficient starts at 1 (``"auto_<x>"``: at ``x``) and its optimizer is Adam at the
algorithm's learning rate, following its schedule. The coefficient each batch's loss uses is alpha
before that batch's step on it (SAC's order). It is kept as ``ent_coef_init * exp(log_ent_coef_ratio)``
with the learned ``log_ent_coef_ratio = log(alpha / ent_coef_init)`` starting at 0 (the same Adam steps
as on ``log alpha``), so that with ``ent_coef_lr=0`` the coefficient is ``ent_coef_init`` exactly and a
seeded run is the stock algorithm's at that fixed coefficient, bit for bit. A float ``ent_coef`` is a fixed
coefficient: the class is then the stock algorithm.

On TwoDimA2C and TwoDimPPO the entropy that drives alpha is that of the tempered policy that acts
(eq. 9, the distribution that drew each action, at the temperature it was drawn at): it is the entropy
whose gradient the algorithms' entropy term already follows
(:meth:`~sb3_twodrl.common.policies.TwoDimPolicyMixin.evaluate_actions_two_dim`), and a Lagrange
multiplier must watch the constrained quantity that the term it weights pushes. It also makes the
arm the question it is run for: exploration the interest already gives (a high temperature) counts
toward the target, so alpha adds a bonus only where the interest's exploration falls short. (The 2D
classes never draw uniformly: ``1/T >= 1/max_temperature > 0``, so every entropy of the batch counts.)

Each ``train`` logs ``train/ent_coef`` (mean of the coefficients used), ``train/ent_coef_loss`` and
``train/entropy`` (mean entropy of the batches that drove alpha) beside the algorithm's own keys, and keeps
the coefficient's course through ``learn``'s budget in ``ent_coef_course`` (saved with the model): per tenth
``d`` of the budget, ``[num_timesteps, alpha, entropy / maximum entropy]`` of the last ``train`` in it, the
means over its batches (None for a tenth with no ``train``), so a run's course is read from its final model;
``ent_coef_latest`` holds the last ``train``'s (for a run whose ``learn`` has no set budget, such as the
paper's epochs, which read it per epoch).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator
from typing import Any, ClassVar

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.policies import ActorCriticCnnPolicy, BasePolicy, MultiInputActorCriticPolicy
from stable_baselines3.common.type_aliases import PyTorchObs
from stable_baselines3.common.utils import update_learning_rate

from sb3_twodrl import TwoDimA2C, TwoDimPPO
from sb3_twodrl.common.validation import check_non_negative, is_real
from twodrl_bench.algorithms.baselines import FastA2C, FastActorCriticPolicy, FastPPO

TARGET_FRACTION = 0.98
"""The default target, as a fraction of the maximum entropy: SAC-Discrete's ``0.98 * -log(1/|A|)``
(Christodoulou 2019, arXiv:1910.07207)."""
COURSE_POINTS = 10
"""Points of ``ent_coef_course``: the coefficient at the end of each tenth of ``learn``'s budget."""


def max_entropy(action_space: spaces.Space) -> float:
    """The largest entropy a policy over ``action_space`` can have (the uniform policy's).

    :raises ValueError: for a ``Box`` or any other space without one
    """
    if isinstance(action_space, spaces.Discrete):
        return math.log(int(action_space.n))
    if isinstance(action_space, spaces.MultiDiscrete):
        return float(np.log(action_space.nvec.astype(np.float64)).sum())
    if isinstance(action_space, spaces.MultiBinary):
        return float(np.prod(action_space.shape)) * math.log(2.0)
    raise ValueError(
        f"action_space must be Discrete, MultiDiscrete or MultiBinary, got {action_space!r}: the target entropy "
        "is a fraction of the maximum entropy, which a Gaussian policy over a Box has not"
    )


def parse_ent_coef(ent_coef: float | str) -> tuple[bool, float]:
    """``(learned, initial value)`` of an ``ent_coef`` argument: ``"auto"`` (learned from 1, SAC's default),
    ``"auto_<x>"`` (learned from ``x > 0``) or a fixed coefficient ``>= 0``.

    :raises ValueError: naming ``ent_coef`` and its value otherwise
    """
    if isinstance(ent_coef, str):
        head, _, init = ent_coef.partition("_")
        value = math.nan
        if head == "auto":
            with contextlib.suppress(ValueError):
                value = float(init) if init else 1.0
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f'ent_coef must be "auto", "auto_<initial value > 0>" or a float >= 0, got {ent_coef!r}')
        return True, value
    check_non_negative("ent_coef", ent_coef)
    return False, float(ent_coef)


class AutoEntropyMixin:
    """SAC's learned entropy coefficient on an SB3 on-policy algorithm; goes before the algorithm's class.

    The entropy of each gradient step's batch reaches :meth:`_tune_ent_coef` through the policy's
    ``evaluate_actions`` (stock algorithms, :class:`EntropyObservingPolicyMixin`) or the algorithm's
    ``_evaluate_actions`` (2D-RL).
    """

    # The algorithm's attributes that the mixin uses
    action_space: spaces.Space
    device: th.device
    ent_coef: float
    lr_schedule: Callable[[float], float]
    logger: Any
    policy: Any
    _current_progress_remaining: float
    num_timesteps: int

    def __init__(
        self,
        policy: str | type[BasePolicy],
        env: Any,
        *args: Any,
        ent_coef: float | str = "auto",
        target_entropy_fraction: float = TARGET_FRACTION,
        ent_coef_lr: float | None = None,
        **kwargs: Any,
    ):
        """:param ent_coef: ``"auto"`` (learned, from 1), ``"auto_<x>"`` (learned, from ``x``) or a fixed coefficient
        :param target_entropy_fraction: the target entropy as a fraction of the maximum, in (0, 1]
        :param ent_coef_lr: the coefficient's Adam learning rate; None: the algorithm's (its schedule, as SAC)

        Every other argument is the algorithm's.
        """
        self.ent_coef_auto, self.ent_coef_init = parse_ent_coef(ent_coef)
        if not (is_real(target_entropy_fraction) and 0.0 < target_entropy_fraction <= 1.0):
            raise ValueError(f"target_entropy_fraction must be in (0, 1], got {target_entropy_fraction!r}")
        if ent_coef_lr is not None:
            check_non_negative("ent_coef_lr", ent_coef_lr)
        self.target_entropy_fraction = target_entropy_fraction
        self.ent_coef_lr = ent_coef_lr
        self.target_entropy: float | None = None
        self.log_ent_coef_ratio: th.Tensor | None = None
        self.ent_coef_optimizer: th.optim.Adam | None = None
        self._ent_coef_stats: list[tuple[float, float, float]] = []
        self.ent_coef_latest: list[float] | None = None
        self.ent_coef_course: list[list[float] | None] = [None] * COURSE_POINTS
        super().__init__(policy, env, *args, ent_coef=self.ent_coef_init, **kwargs)  # type: ignore[call-arg]

    def _setup_model(self) -> None:
        if self.ent_coef_auto:
            self.target_entropy = self.target_entropy_fraction * max_entropy(self.action_space)
        super()._setup_model()  # type: ignore[misc]
        if self.ent_coef_auto:
            self.log_ent_coef_ratio = th.zeros(1, device=self.device, requires_grad=True)
            self.ent_coef_optimizer = th.optim.Adam([self.log_ent_coef_ratio], lr=self._ent_coef_learning_rate())

    def _ent_coef_learning_rate(self) -> float:
        """``ent_coef_lr``, or the algorithm's learning rate now (SAC: the same schedule as the networks')."""
        if self.ent_coef_lr is not None:
            return self.ent_coef_lr
        return self.lr_schedule(self._current_progress_remaining)

    def _tune_ent_coef(self, entropy: th.Tensor) -> None:
        """Set ``ent_coef`` to the current alpha for this batch's loss, then take alpha's step on the batch's
        entropies: loss ``-log(alpha) * (H_target - H)``, averaged."""
        assert self.log_ent_coef_ratio is not None and self.ent_coef_optimizer is not None
        assert self.target_entropy is not None
        self.ent_coef = self.ent_coef_init * math.exp(self.log_ent_coef_ratio.item())
        entropy = entropy.detach()
        log_ent_coef = math.log(self.ent_coef_init) + self.log_ent_coef_ratio
        loss = -(log_ent_coef * (self.target_entropy - entropy)).mean()
        self.ent_coef_optimizer.zero_grad()
        loss.backward()
        self.ent_coef_optimizer.step()
        self._ent_coef_stats.append((self.ent_coef, loss.item(), entropy.mean().item()))

    def _observing_entropy(self) -> contextlib.AbstractContextManager[None]:
        """While ``train`` runs: pass each gradient step's entropy to :meth:`_tune_ent_coef` (default: nothing)."""
        return contextlib.nullcontext()

    def train(self) -> None:
        if not self.ent_coef_auto:
            super().train()  # type: ignore[misc]
            return
        assert self.ent_coef_optimizer is not None
        update_learning_rate(self.ent_coef_optimizer, self._ent_coef_learning_rate())
        self._ent_coef_stats = []
        with self._observing_entropy():
            super().train()  # type: ignore[misc]
        coefficients, losses, entropies = zip(*self._ent_coef_stats, strict=True)
        self.logger.record("train/ent_coef", float(np.mean(coefficients)))
        self.logger.record("train/ent_coef_loss", float(np.mean(losses)))
        self.logger.record("train/entropy", float(np.mean(entropies)))
        entropy_fraction = float(np.mean(entropies)) / max_entropy(self.action_space)
        self.ent_coef_latest = [int(self.num_timesteps), float(np.mean(coefficients)), entropy_fraction]
        done = 1.0 - self._current_progress_remaining  # of learn's budget, as the schedules read it
        point = min(COURSE_POINTS, max(1, math.ceil(COURSE_POINTS * done - 1e-9)))
        self.ent_coef_course[point - 1] = self.ent_coef_latest

    def _get_torch_save_params(self) -> tuple[list[str], list[str]]:
        state_dicts, variables = super()._get_torch_save_params()  # type: ignore[misc]
        if self.ent_coef_auto:
            return [*state_dicts, "ent_coef_optimizer"], [*variables, "log_ent_coef_ratio"]
        return state_dicts, variables

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "_ent_coef_stats"]  # type: ignore[misc]


class EntropyObservingPolicyMixin:
    """A policy whose ``evaluate_actions`` hands each batch's entropy to its ``entropy_observer`` (if any) before
    returning it: how SB3's A2C and PPO, whose ``train`` asks the policy, let the algorithm see the entropy."""

    entropy_observer: Callable[[th.Tensor], None] | None = None

    def evaluate_actions(self, obs: PyTorchObs, actions: th.Tensor) -> tuple[th.Tensor, th.Tensor, th.Tensor | None]:
        values, log_prob, entropy = super().evaluate_actions(obs, actions)  # type: ignore[misc]
        if self.entropy_observer is not None:
            self.entropy_observer(entropy)  # never None: the spaces with a maximum entropy have it in closed form
        return values, log_prob, entropy


class EntropyObservingActorCriticPolicy(EntropyObservingPolicyMixin, FastActorCriticPolicy):
    """The stock arms' ``MlpPolicy`` (:class:`~twodrl_bench.algorithms.baselines.FastActorCriticPolicy`)."""


class EntropyObservingCnnPolicy(EntropyObservingPolicyMixin, ActorCriticCnnPolicy):
    """SB3's ``CnnPolicy``."""


class EntropyObservingMultiInputPolicy(EntropyObservingPolicyMixin, MultiInputActorCriticPolicy):
    """SB3's ``MultiInputPolicy``."""


_OBSERVING_POLICIES: dict[str, type[BasePolicy]] = {
    "MlpPolicy": EntropyObservingActorCriticPolicy,
    "CnnPolicy": EntropyObservingCnnPolicy,
    "MultiInputPolicy": EntropyObservingMultiInputPolicy,
}


class _StockAutoEntropyMixin(AutoEntropyMixin):
    """For SB3's A2C and PPO, whose ``train`` asks ``policy.evaluate_actions`` for each batch's entropy: their
    policies are :class:`EntropyObservingPolicyMixin` ones, whose observer is :meth:`_tune_ent_coef` while
    ``train`` runs (so that no checkpoint holds it)."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = _OBSERVING_POLICIES

    def _setup_model(self) -> None:
        super()._setup_model()
        if self.ent_coef_auto and not isinstance(self.policy, EntropyObservingPolicyMixin):
            raise TypeError(
                f"policy must be one of {sorted(_OBSERVING_POLICIES)} or an EntropyObservingPolicyMixin subclass "
                f"with a learned ent_coef, got {type(self.policy).__name__}"
            )

    @contextlib.contextmanager
    def _observing_entropy(self) -> Iterator[None]:
        self.policy.entropy_observer = self._tune_ent_coef
        try:
            yield
        finally:
            self.policy.entropy_observer = None


class _TwoDimAutoEntropyMixin(AutoEntropyMixin):
    """For TwoDimA2C and TwoDimPPO, whose ``train`` asks ``_evaluate_actions``: alpha follows the entropy of the
    tempered policy that acts (eq. 9), the one their entropy term pushes."""

    def _evaluate_actions(
        self, observations: Any, actions: th.Tensor, inverse_temperatures: th.Tensor
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
        out = super()._evaluate_actions(observations, actions, inverse_temperatures)  # type: ignore[misc]
        if self.ent_coef_auto:
            self._tune_ent_coef(out[4])
        return out


class AutoEntropyA2C(_StockAutoEntropyMixin, FastA2C):
    """SB3's ``A2C`` (the bench's :class:`~twodrl_bench.algorithms.baselines.FastA2C`) with SAC's learned entropy
    coefficient: ``ent_coef``, ``target_entropy_fraction`` and ``ent_coef_lr`` as :class:`AutoEntropyMixin`'s;
    every other argument is ``A2C``'s."""


class AutoEntropyPPO(_StockAutoEntropyMixin, FastPPO):
    """SB3's ``PPO`` (the bench's :class:`~twodrl_bench.algorithms.baselines.FastPPO`) with SAC's learned entropy
    coefficient, one step of it per minibatch. ``ent_coef``, ``target_entropy_fraction`` and ``ent_coef_lr``
    as :class:`AutoEntropyA2C`'s; every other argument is ``PPO``'s."""


class AutoEntropyTwoDimA2C(_TwoDimAutoEntropyMixin, TwoDimA2C):
    """``TwoDimA2C`` with SAC's learned entropy coefficient, driven by the entropy of the tempered policy
    that acts (eq. 9). ``ent_coef``, ``target_entropy_fraction`` and ``ent_coef_lr`` as
    :class:`AutoEntropyA2C`'s; every other argument is ``TwoDimA2C``'s."""


class AutoEntropyTwoDimPPO(_TwoDimAutoEntropyMixin, TwoDimPPO):
    """``TwoDimPPO`` with SAC's learned entropy coefficient, driven by the entropy of the tempered policy
    that acts (eq. 9), one step of it per minibatch. ``ent_coef``, ``target_entropy_fraction`` and
    ``ent_coef_lr`` as :class:`AutoEntropyA2C`'s; every other argument is ``TwoDimPPO``'s."""
