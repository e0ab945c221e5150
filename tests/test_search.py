"""The baseline settings search (``sb3-twodrl-search``): its grid, its scores, a tiny run and its resume."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from twodrl_bench import search


def test_grid_items_become_lists_of_literals() -> None:
    grid = search.parse_grid(["learning_rate:3e-4,1e-3", "n_epochs:4", "policy:'MlpPolicy',"])
    assert grid == {"learning_rate": [3e-4, 1e-3], "n_epochs": [4], "policy": ["MlpPolicy"]}
    assert search.point_name({"learning_rate": 3e-4, "n_epochs": 4}) == "learning_rate=0.0003_n_epochs=4"


@pytest.mark.parametrize("items", [["learning_rate"], ["n_epochs:4", "n_epochs:10"], ["lr:3e-4,,"]])
def test_a_bad_grid_is_refused(items: list[str]) -> None:
    with pytest.raises(ValueError, match="grid"):
        search.parse_grid(items)


def test_score_epochs_outside_the_run_are_refused() -> None:
    with pytest.raises(ValueError, match="score_epochs"):
        search.parse_args(["--grid", "n_epochs:4", "--epochs", "20", "--score-epochs", "11", "21"])


def test_the_scores_read_the_window_and_the_first_epoch_at_half() -> None:
    epochs = np.arange(1, 21)
    rows = pd.DataFrame(
        {
            "seed": np.repeat([0, 1], 20),
            "epoch": np.tile(epochs, 2),
            "goal_rate": np.r_[np.where(epochs >= 5, 1.0, 0.0), np.zeros(20)],
            "reward_per_step": np.r_[np.where(epochs >= 11, 0.3, 0.0), np.full(20, -0.01)],
        }
    )
    s = search.score(rows, 11, 20)
    assert s["per_seed"][0] == {"goal_rate": 0.8, "reward_per_step": pytest.approx(0.3), "first_half": 5}
    assert s["per_seed"][1]["first_half"] is None
    assert s["reward_per_step"] == pytest.approx(0.145) and s["goal_rate"] == pytest.approx(0.4)


def test_a_tiny_search_runs_every_point_ranks_them_and_resumes(tmp_path: Path) -> None:
    argv = ["--algo", "ppo", "--grid", "n_epochs:1,2", "--set", "n_envs:2", "n_steps:8", "batch_size:16"]
    argv += ["--epochs", "2", "-K", "2", "-M", "1", "--seeds", "0", "--backend", "serial", "--out", str(tmp_path)]
    results = search.search(argv)
    assert sorted(r["n_epochs"] for r in results) == [1, 2]
    scores = [r["reward_per_step"] for r in results]
    assert all(math.isfinite(v) for v in scores) and scores == sorted(scores, reverse=True)
    pairs = sorted(tmp_path.glob("NomadOffice-v0/ppo/*/pairs/ppo_seed0.csv"))
    assert [p.parent.parent.name for p in pairs] == ["n_epochs=1", "n_epochs=2"]
    stamps = [p.stat().st_mtime_ns for p in pairs]
    assert search.search(argv) == results and [p.stat().st_mtime_ns for p in pairs] == stamps
