"""Cheap statistics for the training loop, where a numpy call with a Python layer costs several times more."""

import numpy as np
import torch as th


def flat(values: th.Tensor) -> np.ndarray:
    """A critic's output ``(n_envs, 1)`` as a flat numpy array."""
    return values.cpu().numpy().ravel()


def fast_mean(values: np.ndarray) -> float:
    """``values.mean()`` by way of ``sum``: inside the training loop ``ndarray.mean`` costs several times more."""
    return float(values.sum()) / values.size


def fast_variance(values: np.ndarray) -> float:
    """``values.var()`` by way of :func:`fast_mean`, for the same reason."""
    deviations = values - fast_mean(values)
    return fast_mean(deviations * deviations)


def fast_explained_variance(predictions: np.ndarray, targets: np.ndarray) -> float:
    """SB3's ``explained_variance`` (NaN where the targets do not vary) by way of :func:`fast_variance`."""
    target_variance = fast_variance(targets)
    return np.nan if target_variance == 0 else 1.0 - fast_variance(targets - predictions) / target_variance
