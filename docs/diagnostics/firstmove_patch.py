"""Exploratory diagnostic (docs/ablation.md): the compensated score without its update at an episode's
uniform first move (1/T = 0), where it is A * (1[a] - 1/4) whatever the policy. Imported in each worker
as a "gym package": registers the envs, then masks the score and entropy of the 1/T = 0 samples."""

import torch as th

import envs  # noqa: F401
from sb3_twodrl.common.policies import TwoDimPolicyMixin

_original = TwoDimPolicyMixin.evaluate_actions_two_dim


def _masked(self, obs, actions, score="log_prob", inverse_temperature=None):
    values, punishment, predicted, scores, entropy = _original(self, obs, actions, score, inverse_temperature)
    if score == "compensated":
        keep = (th.as_tensor(inverse_temperature, device=scores.device).reshape(-1) > 0).to(scores.dtype)
        scores = scores * keep
        entropy = None if entropy is None else entropy * keep
    return values, punishment, predicted, scores, entropy


TwoDimPolicyMixin.evaluate_actions_two_dim = _masked
