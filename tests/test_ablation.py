"""The ablation: arms differ only in their 2D settings, the fixed arms take the paper arm's temperature."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest

from twodrl_bench import ablation
from twodrl_bench.grid import collect_results

BASE = {
    "a2c": {"n_envs": 4, "n_steps": 5, "gamma": 0.9, "learning_rate": 3e-3},
    "twoda2c": {"n_envs": 4, "n_steps": 5, "gamma": 0.9, "learning_rate": 3e-3, "punishment_gamma": 0.1},
    "ppo": {"n_envs": 4, "n_steps": 16, "gamma": 0.9, "n_epochs": 4},
    "twodppo": {"n_envs": 4, "n_steps": 16, "gamma": 0.9, "n_epochs": 4, "punishment_gamma": 0.1},
}


@pytest.mark.parametrize("arm", sorted(ablation.ARMS))
def test_arms_share_every_non_2d_setting(arm: str) -> None:
    algo, hp = ablation.arm_hyperparams(arm, BASE, temperature=0.7)
    stock = "ppo" if "ppo" in arm else "a2c"
    for key, value in BASE[stock].items():
        assert hp[key] == value, key
    assert (algo == stock) == (arm == stock)
    if arm in ablation.FIXED:
        assert hp["temperature"] == 0.7 and hp.get("preferences", "raw") == "raw"
    else:
        assert "temperature" not in hp
    if arm == "a2c_fixed":
        assert hp["reward_split"] == "none" and hp["punishment_weight"] == 0.0 == hp["punishment_vf_coef"]


def test_a_fixed_arm_without_a_temperature_is_an_error() -> None:
    with pytest.raises(ValueError, match="twod_fixed"):
        ablation.arm_hyperparams("twod_fixed", BASE, temperature=None)
    with pytest.raises(ValueError, match="arm must be one of"):
        ablation.arm_hyperparams("softmax", BASE, temperature=None)


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
    argv = ["--out", str(tmp_path), "--seeds", "0", "--epochs", "2", "-K", "4", "-M", "3", "--backend", "serial"]
    runs = ablation.ablation([*argv, "--arms", "a2c", "paper", "twod_fixed", "relative_bounded"])
    assert sorted(runs) == ["a2c", "paper", "relative_bounded", "twod_fixed"]
    assert all(len(mine) == 1 for mine in runs.values())
    assert math.isnan(runs["a2c"][0]["interest_share"]) and runs["twod_fixed"][0]["interest_share"] == 0.0
    assert 0.0 < runs["relative_bounded"][0]["interest_share"] <= 1.0
    paper = collect_results(tmp_path / "paper")
    temperature = json.loads((tmp_path / "fixed_temperature.json").read_text())["temperature"]
    assert temperature == pytest.approx(ablation.mean_temperature(paper)) and temperature >= 0.5
    fixed = collect_results(tmp_path / "twod_fixed")
    assert fixed["mean_temperature"].dropna().to_numpy() == pytest.approx(temperature, rel=1e-5)
    assert (tmp_path / "table.md").read_text().count("\n") == 2 + 4 and (tmp_path / "ablation.png").exists()


def test_a_fixed_arm_alone_runs_in_a_new_folder_at_the_given_temperature(tmp_path: Path) -> None:
    out = tmp_path / "new"
    argv = ["--out", str(out), "--seeds", "0", "--epochs", "1", "-K", "4", "-M", "3", "--backend", "serial"]
    ablation.ablation([*argv, "--arms", "twod_fixed_compensated", "--fixed-temperature", "1.25"])
    assert json.loads((out / "fixed_temperature.json").read_text())["temperature"] == 1.25
    rows = collect_results(out / "twod_fixed_compensated")
    assert rows["mean_temperature"].dropna().to_numpy() == pytest.approx(1.25, rel=1e-5)


def test_the_figure_takes_arms_whose_every_seed_learned(tmp_path: Path) -> None:
    """10 of 10 seeds learned: the interval's upper end equals the mean up to rounding (no negative error bar)."""
    learned = [ablation.summarize_run(rows([0.2, 1.0, 1.0], [0.1, 0.1, 0.1])) for _ in range(10)]
    frames = {"a2c": pd.DataFrame({"epoch": [1, 2, 3], "goal_rate": [0.2, 1.0, 1.0]})}
    ablation.figure(frames, {"a2c": learned}, tmp_path / "ablation.png")
    assert (tmp_path / "ablation.png").exists()


def test_the_report_of_results_files_is_that_of_the_runs(tmp_path: Path) -> None:
    """``--from-results`` rebuilds the table of earlier runs from their committed rows, without running."""
    argv = ["--out", str(tmp_path / "run"), "--seeds", "0", "1", "--epochs", "2", "-K", "4", "-M", "3"]
    runs = ablation.ablation([*argv, "--backend", "serial", "--arms", "a2c", "paper"])
    paths = []
    for arm in ("a2c", "paper"):
        rows = collect_results(tmp_path / "run" / arm)
        rows.insert(0, "arm", arm)
        paths.append(tmp_path / f"{arm}.csv")
        rows.to_csv(paths[-1], index=False)
    again = ablation.ablation(["--out", str(tmp_path / "report"), "--from-results", *map(str, paths)])
    assert json.dumps(again) == json.dumps(runs)  # NaN-aware
    assert (tmp_path / "report" / "table.md").read_text() == (tmp_path / "run" / "table.md").read_text()
    with pytest.raises(ValueError, match="more than one file"):
        ablation.ablation(["--out", str(tmp_path / "twice"), "--from-results", str(paths[0]), str(paths[0])])


def test_a_factorial_cell_changes_the_shared_settings_and_the_env_for_every_arm(tmp_path: Path) -> None:
    argv = ["--out", str(tmp_path), "--seeds", "0", "--epochs", "1", "-K", "4", "-M", "3", "--backend", "serial"]
    cell = ["--set", "ent_coef:0.01", "n_envs:2", "policy_kwargs:{'net_arch':[]}", "--env-kwargs", "observation:'cell'"]
    ablation.ablation([*argv, "--arms", "a2c", "twoda2c", *cell])
    for arm, algo in (("a2c", "a2c"), ("twoda2c", "twoda2c")):
        config = json.loads((tmp_path / arm / "config.json").read_text())
        assert config["env_kwargs"] == {"observation": "cell"}
        settings = config["hyperparams"][algo]
        changed = (settings["ent_coef"], settings["n_envs"], settings["policy_kwargs"])
        assert changed == ("0.01", "2", "{'net_arch': []}")
    with pytest.raises(ValueError, match="--set"):
        ablation.ablation([*argv, "--arms", "a2c", "--set", "ent_coef=0.01"])


def test_the_ppo_arms_run_on_ppos_files_with_the_cells_settings(tmp_path: Path) -> None:
    argv = ["--out", str(tmp_path), "--seeds", "0", "--epochs", "1", "-K", "4", "-M", "3", "--backend", "serial"]
    ablation.ablation([*argv, "--arms", "ppo", "twodppo", "--set", "n_envs:2", "n_steps:8", "batch_size:16"])
    for arm in ("ppo", "twodppo"):
        settings = json.loads((tmp_path / arm / "config.json").read_text())["hyperparams"][arm]
        assert (settings["n_envs"], settings["n_steps"], settings["n_epochs"]) == ("2", "8", "10")
        assert ("punishment_gamma" in settings) == (arm == "twodppo")
        assert len(collect_results(tmp_path / arm)) == 1
