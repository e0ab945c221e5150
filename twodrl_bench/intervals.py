"""95% intervals over seeds: Student t for means, Wilson for shares, Welch for differences of means."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

Z95 = 1.959964


def t_quantile(n: int) -> float:
    """Two-sided 95% Student t quantile with n - 1 degrees of freedom (NaN for n < 2)."""
    from scipy import stats

    return float(stats.t.ppf(0.975, n - 1)) if n >= 2 else math.nan


def mean_ci(values: Iterable[float]) -> tuple[float, float, int]:
    """Mean and the half-width of its 95% t-interval over the finite values, and their number."""
    v = np.asarray([x for x in values if np.isfinite(x)], dtype=float)
    if v.size == 0:
        return math.nan, math.nan, 0
    if v.size == 1:
        return float(v[0]), math.nan, 1
    return float(v.mean()), float(t_quantile(v.size) * v.std(ddof=1) / math.sqrt(v.size)), int(v.size)


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """95% Wilson score interval of a proportion k / n."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def welch_ci(a: Iterable[float], b: Iterable[float]) -> tuple[float, float]:
    """Difference of means ``mean(a) - mean(b)`` and the half-width of its 95% Welch interval."""
    from scipy import stats

    x, y = np.asarray(list(a), dtype=float), np.asarray(list(b), dtype=float)
    va, vb = x.var(ddof=1) / x.size, y.var(ddof=1) / y.size
    dof = (va + vb) ** 2 / (va**2 / (x.size - 1) + vb**2 / (y.size - 1)) if va + vb > 0 else 1.0
    return float(x.mean() - y.mean()), float(stats.t.ppf(0.975, dof) * math.sqrt(va + vb))
