"""``torch.distributions.Categorical``'s formulas on plain tensors, and a multi-tensor optimizer: the same
numbers, bit for bit, with less Python around them.

A rollout step of a small MLP policy costs more in Python than in arithmetic: SB3's
``CategoricalDistribution`` builds a ``Categorical`` per call (its argument checks, its lazy properties),
which costs as much as a layer's matmul. :func:`categorical_sample`, :func:`categorical_log_prob` and
:func:`categorical_entropy` are ``Categorical``'s own formulas on the normalized logits
(:func:`normalized`); :func:`build_optimizer` makes the optimizer multi-tensor. The 2D-RL policy's
rollout and update of ``Discrete`` actions run on them; only public torch and SB3 API is used.
"""

import inspect
from collections.abc import Callable

import torch as th
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.type_aliases import Schedule
from torch.nn import functional as F


def normalized(logits: th.Tensor) -> th.Tensor:
    """``Categorical(logits=...).logits``: log-probabilities."""
    return logits - logits.logsumexp(dim=-1, keepdim=True)


def categorical_sample(log_probs: th.Tensor) -> th.Tensor:
    """``Categorical.sample()`` from normalized logits: one action per row, the same random draws."""
    return th.multinomial(F.softmax(log_probs, dim=-1), 1, True).T.reshape(-1)


def categorical_log_prob(log_probs: th.Tensor, actions: th.Tensor) -> th.Tensor:
    """``Categorical.log_prob(actions)`` from normalized logits."""
    return log_probs.gather(-1, actions.long().unsqueeze(-1)).squeeze(-1)


def categorical_entropy(log_probs: th.Tensor) -> th.Tensor:
    """``Categorical.entropy()`` from normalized logits."""
    clamped = th.clamp(log_probs, min=th.finfo(log_probs.dtype).min)
    return -(clamped * F.softmax(log_probs, dim=-1)).sum(-1)


def build_optimizer(policy: ActorCriticPolicy, lr_schedule: Schedule) -> th.optim.Optimizer:
    """The policy's optimizer over all its parameters, multi-tensor (``foreach=True``) where the optimizer
    class takes it and ``optimizer_kwargs`` does not say otherwise: one kernel per operation for all
    the parameters instead of one per parameter, the same numbers (PyTorch's RMSprop and Adam, tested)."""
    kwargs = dict(policy.optimizer_kwargs)
    optimizer_class: Callable[..., th.optim.Optimizer] = policy.optimizer_class  # a subclass: it takes lr
    if "foreach" in inspect.signature(optimizer_class).parameters:
        kwargs.setdefault("foreach", True)
    return optimizer_class(policy.parameters(), lr=lr_schedule(1), **kwargs)
