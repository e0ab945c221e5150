"""SB3's actor-critic forward pass as plain tensor operations: the same operations, bit for bit, with
less Python around them.

At 64 envs a rollout step of a small MLP policy costs more in Python than in arithmetic: each
``nn.Module`` call, each ``torch.distributions.Categorical`` (its argument checks, its lazy
properties) costs as much as a layer's matmul. :func:`latents` runs SB3's ``MlpExtractor`` layer by
layer with ``torch.nn.functional`` (any other extractor, or a module with hooks, through its own
``forward``); :func:`categorical_sample`, :func:`categorical_log_prob` and :func:`categorical_entropy`
are ``Categorical``'s own formulas; :func:`build_optimizer` makes the optimizer multi-tensor. The 2D-RL
policy's rollout and update run on them.

Measured gain, with :mod:`sb3_twodrl.common.utils`' statistics: ``TwoDimA2C``/``TwoDimPPO`` against
themselves with SB3's module calls, SB3's ``CategoricalDistribution``, a per-parameter optimizer and
numpy's statistics (the same parameters bit for bit, ``tests/test_fast.py``), env steps per CPU second,
one torch thread, alternating runs, median of 3, on a loaded 2-core machine (``scripts/bench_algo.py
--pairs a2c-layer ppo-layer``; ``docs/speed.md``): TwoDimA2C 1.23x and TwoDimPPO 1.22x on
CartPole-v1 (8 envs, defaults), TwoDimA2C 1.20x on the batched NomadOffice-v0 (64 envs).
"""

import inspect

import torch as th
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import MlpExtractor
from stable_baselines3.common.type_aliases import PyTorchObs, Schedule
from torch import nn
from torch.nn import functional as F

_ACTIVATIONS = {nn.Tanh: th.tanh, nn.ReLU: F.relu, nn.Identity: lambda x: x}


def _hooked(module: nn.Module) -> bool:
    return bool(module._forward_hooks or module._forward_pre_hooks)


def run_sequential(net: nn.Module, x: th.Tensor) -> th.Tensor:
    """``net(x)`` for an ``nn.Sequential`` of ``nn.Linear`` and Tanh/ReLU layers, as ``torch.nn.functional``
    calls; any other module (or one with hooks) is called as it is."""
    if type(net) is not nn.Sequential or _hooked(net):
        return net(x)
    for layer in net:
        if type(layer) is nn.Linear and not _hooked(layer):
            x = F.linear(x, layer.weight, layer.bias)
        elif type(layer) in _ACTIVATIONS and not _hooked(layer) and not getattr(layer, "inplace", False):
            x = _ACTIVATIONS[type(layer)](x)
        else:
            x = layer(x)
    return x


def _plain_extractor(policy: ActorCriticPolicy) -> bool:
    """Whether the extractor is SB3's own ``MlpExtractor`` without hooks, which :func:`run_sequential` may run."""
    return type(policy.mlp_extractor) is MlpExtractor and not _hooked(policy.mlp_extractor)


def latents(policy: ActorCriticPolicy, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
    """The actor's and the critic's latent features of ``obs``, as ``ActorCriticPolicy.forward`` computes them."""
    features = policy.extract_features(obs)
    pi_features, vf_features = (features, features) if policy.share_features_extractor else features
    extractor = policy.mlp_extractor
    if _plain_extractor(policy):
        return run_sequential(extractor.policy_net, pi_features), run_sequential(extractor.value_net, vf_features)
    if policy.share_features_extractor:
        return extractor(features)
    return extractor.forward_actor(pi_features), extractor.forward_critic(vf_features)


def critic_latent(policy: ActorCriticPolicy, vf_features: th.Tensor) -> th.Tensor:
    """The critic's latent features, as ``mlp_extractor.forward_critic`` computes them."""
    extractor = policy.mlp_extractor
    if _plain_extractor(policy):
        return run_sequential(extractor.value_net, vf_features)
    return extractor.forward_critic(vf_features)


def actor_latent(policy: ActorCriticPolicy, pi_features: th.Tensor) -> th.Tensor:
    """The actor's latent features, as ``mlp_extractor.forward_actor`` computes them."""
    extractor = policy.mlp_extractor
    if _plain_extractor(policy):
        return run_sequential(extractor.policy_net, pi_features)
    return extractor.forward_actor(pi_features)


def linear(layer: nn.Module, x: th.Tensor) -> th.Tensor:
    """``layer(x)`` for an ``nn.Linear`` head, without the module call."""
    if type(layer) is nn.Linear and not _hooked(layer):
        return F.linear(x, layer.weight, layer.bias)
    return layer(x)


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
    if "foreach" in inspect.signature(policy.optimizer_class).parameters:
        kwargs.setdefault("foreach", True)
    return policy.optimizer_class(policy.parameters(), lr=lr_schedule(1), **kwargs)
