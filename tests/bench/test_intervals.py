"""twodrl_bench.intervals: the intervals contain their estimate and agree with scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from twodrl_bench.intervals import mean_ci, welch_ci, wilson

pytest.importorskip("scipy")


@given(st.integers(1, 500).flatmap(lambda n: st.tuples(st.integers(0, n), st.just(n))))
def test_wilson_contains_the_share_and_stays_in_the_unit_interval(kn) -> None:
    k, n = kn
    low, high = wilson(k, n)
    assert 0.0 <= low <= k / n + 1e-12 and k / n - 1e-12 <= high <= 1.0


def test_mean_ci_matches_scipy_and_skips_nan() -> None:
    from scipy import stats

    x = [0.1, 0.4, 0.35, 0.8, math.nan]
    mean, half, n = mean_ci(x)
    low, high = stats.t.interval(0.95, 3, loc=np.mean(x[:4]), scale=stats.sem(x[:4]))
    assert n == 4 and mean == pytest.approx(np.mean(x[:4])) and mean - half == pytest.approx(low)
    assert mean + half == pytest.approx(high)
    assert math.isnan(mean_ci([2.0])[1]) and mean_ci([])[2] == 0


def test_welch_matches_scipy() -> None:
    from scipy import stats

    a, b = [1.0, 2.0, 4.0, 3.5], [0.0, 0.5, 2.0]
    d, half = welch_ci(a, b)
    res = stats.ttest_ind(a, b, equal_var=False).confidence_interval(0.95)
    assert d - half == pytest.approx(res.low) and d + half == pytest.approx(res.high)
