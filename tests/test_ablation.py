"""scripts/ablation.py: the arms differ only in their 2D settings, and a run reports every metric."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
from stable_baselines3 import A2C

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

import ablation  # noqa: E402

from sb3_twodrl import TwoDimA2C  # noqa: E402


@pytest.mark.parametrize("arm", ablation.ARMS)
def test_arms_share_every_non_2d_setting(arm: str) -> None:
    model = ablation.make_model(arm, seed=0, temperature=0.5)
    assert type(model) is (A2C if arm == "a2c" else TwoDimA2C)
    for name, value in ablation.SHARED.items():
        assert getattr(model, name) == value or str(getattr(model, name)) == value, name
    if arm in ("a2c_fixed", "twod_fixed"):
        assert model.temperature == 0.5 and model.preferences == "raw"
    if arm == "a2c_fixed":
        assert model.punishment_weight == 0.0 and model.punishment_vf_coef == 0.0


def test_a_run_reports_every_metric() -> None:
    result = ablation.run("relative_bounded", seed=0, epochs=2, epoch_steps=320, robots=4, temperature=None)
    assert len(result["goal_rates"]) == 2
    for key in ablation.METRICS:
        assert key in result
    assert 0.0 < result["interest_share"] <= 1.0
    assert result["mean_temperature"] > 0
    mean, low, high, n = ablation.interval([0.0, 1.0, 1.0, 0.0], count=True)
    assert n == 4 and low < mean == 0.5 < high and not math.isnan(low)
