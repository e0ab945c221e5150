"""The ablation (docs/ablation.md): its spec's arms change only 2D-RL settings; its report's metrics."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
import pytest

from twodrl_bench.experiment import Experiment
from twodrl_bench.reports import ablation, find_parts
from twodrl_bench.runner import run_study
from twodrl_bench.spec import load_spec

SPEC = Experiment.from_spec("ablation").as_dict()
FIXED = ("a2c_fixed", "twod_fixed", "twod_fixed_compensated", "twoda2c_fixed")
TWO_D = ("punishment_gamma", "reward_split")


@pytest.mark.parametrize("arm", sorted(SPEC["arms"]))
def test_arms_share_every_non_2d_setting(arm: str) -> None:
    stock = "ppo" if "ppo" in arm else "a2c"
    hp = SPEC["arms"][arm]["hyperparams"]
    for key, value in SPEC["arms"][stock]["hyperparams"].items():
        assert hp[key] == value, key
    assert set(hp) - set(SPEC["arms"][stock]["hyperparams"]) <= {*TWO_D, *SPEC["arms"][arm]["override"]}
    if arm in FIXED:
        assert hp["temperature"] == SPEC["rules"]["fixed_temperature"]["value"]
        assert hp.get("preferences", "raw") == "raw"
    else:
        assert "temperature" not in hp
    if arm == "a2c_fixed":
        assert hp["reward_split"] == "none" and hp["punishment_weight"] == 0.0 == hp["punishment_vf_coef"]
    assert set(SPEC["rules"]["default_arms"]) <= set(SPEC["arms"])


def rows(rates: list[float], shares: list[float]) -> pd.DataFrame:
    steps = [1000 * (i + 1) for i in range(len(rates))]
    metrics = {"shortcut_share": 0.5, "reward_per_step": 0.1}
    return pd.DataFrame({"goal_rate": rates, "env_steps": steps, "interest_share": shares, **metrics})


def test_run_summary_counts_collapse_learning_and_the_interest_share() -> None:
    summary = ablation.summarize_run(rows([0.1, 0.9, 0.4, 0.3, 0.2, 0.9], [0.0, 0.2, 0.2, 0.2, 0.2, 0.2]))
    assert summary["learned"] == 1.0 and summary["epochs_to_half"] == 2.0 and summary["collapsed"] == 1.0
    assert summary["interest_share"] == pytest.approx(1.0 / 6.0)
    held = ablation.summarize_run(rows([0.9, 0.4, 0.3, 0.9, 0.4], [math.nan] * 5))
    assert held["collapsed"] == 0.0 and held["learned"] == 0.0 and math.isnan(held["interest_share"])
    never = ablation.summarize_run(rows([0.0, 0.1], [0.5, 0.5]))
    assert math.isnan(never["epochs_to_half"]) and never["collapsed"] == 0.0


def test_interval_of_a_share_of_seeds() -> None:
    mean, low, high, n = ablation.interval([0.0, 1.0, 1.0, 0.0], count=True)
    assert n == 4 and low < mean == 0.5 < high


def test_tiny_ablation_end_to_end(tmp_path: Path) -> None:
    spec = {**load_spec("ablation"), "seeds": [0], "protocol": {"epochs": 2, "learn_episodes": 4, "test_episodes": 3}}
    spec["arms"] = {arm: spec["arms"][arm] for arm in ("a2c", "paper", "twod_fixed", "relative_bounded")}
    for arm in spec["arms"].values():
        arm["override"] = {**arm["override"], "n_envs": 4}
    run_study(spec, tmp_path, "serial", report=False)
    part = find_parts(tmp_path, "ablation")[0]
    text = ablation.report([part], tmp_path)
    runs = ablation.summaries({arm: g for arm, g in part.rows.groupby("arm")})
    assert sorted(runs) == ["a2c", "paper", "relative_bounded", "twod_fixed"]
    assert math.isnan(runs["a2c"][0]["interest_share"]) and runs["twod_fixed"][0]["interest_share"] == 0.0
    assert 0.0 < runs["relative_bounded"][0]["interest_share"] <= 1.0
    fixed = part.rows[part.rows["arm"] == "twod_fixed"]
    assert fixed["mean_temperature"].to_numpy() == pytest.approx(0.5016, rel=1e-5)
    measured = ablation.mean_temperature(part.rows[part.rows["arm"] == "paper"])
    assert f"arm 'paper' measured {measured:.4f} here" in text
    assert (tmp_path / "table.md").read_text().startswith(text.splitlines()[0])
    assert (tmp_path / "ablation.png").exists() and (tmp_path / "runs.json").exists()


def test_the_figure_takes_arms_whose_every_seed_learned(tmp_path: Path) -> None:
    """10 of 10 seeds learned: the interval's upper end equals the mean up to rounding (no negative error bar)."""
    learned = [ablation.summarize_run(rows([0.2, 1.0, 1.0], [0.1, 0.1, 0.1])) for _ in range(10)]
    height, extents = ablation.error_bar([r["learned"] for r in learned], count=True)
    assert height == 1.0 and extents is not None and extents[1] == [0.0] and extents[0][0] > 0.0
    frames = {"a2c": pd.DataFrame({"epoch": [1, 2, 3], "goal_rate": [0.2, 1.0, 1.0]})}
    ablation.figure(frames, {"a2c": learned}, tmp_path / "ablation.png")  # matplotlib takes the bar as it is
    assert (tmp_path / "ablation.png").stat().st_size > 0
