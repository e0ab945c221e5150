"""Hyperparameter checks: bad values fail at construction with an error naming the argument and the value."""

import math
from typing import Any

import numpy as np


def is_real(value: Any) -> bool:
    """Whether ``value`` is a real number (a Python or numpy int or float, not a bool)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def check_real(name: str, value: Any) -> None:
    """``TypeError`` unless ``value`` is a real number (not a bool)."""
    if not is_real(value):
        raise TypeError(f"{name} must be a real number, got {value!r} of type {type(value).__name__}")


def check_unit_interval(name: str, value: Any) -> None:
    """``TypeError`` unless a real number, ``ValueError`` unless in [0, 1]."""
    check_real(name, value)
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"{name} must be in [0, 1], got {value!r}")


def check_non_negative(name: str, value: Any) -> None:
    """``TypeError`` unless a real number, ``ValueError`` unless finite and >= 0."""
    check_real(name, value)
    if not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"{name} must be finite and >= 0, got {value!r}")


def check_positive(name: str, value: Any) -> None:
    """``TypeError`` unless a real number, ``ValueError`` unless finite and > 0."""
    check_real(name, value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")


def check_positive_int(name: str, value: Any) -> None:
    """``TypeError`` unless an integer (not a bool), ``ValueError`` unless >= 1."""
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool):
        raise TypeError(f"{name} must be an integer, got {value!r} of type {type(value).__name__}")
    if value < 1:
        raise ValueError(f"{name} must be >= 1, got {value!r}")
