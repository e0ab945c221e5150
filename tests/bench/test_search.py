"""The search report: grid points as arms, both scores, the ranking; a changed point cannot reuse old rows."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from twodrl_bench.reports import find_parts, search
from twodrl_bench.runner import run_study
from twodrl_bench.spec import validate


def tiny_search(**rules) -> dict:
    grid = {"algo": "ppo", "points": {"n_epochs": [1, 2]}, "override": {"n_envs": 2, "n_steps": 8, "batch_size": 16}}
    return {
        "name": "tiny_search",
        "env": "NomadOffice-v0",
        "protocol": {"epochs": 2, "learn_episodes": 2, "test_episodes": 1, "save_model": False, "tensorboard": False},
        "seeds": [0],
        "grid": grid,
        "rules": rules,
        "report": "search",
    }


def test_score_epochs_outside_the_run_are_refused(tmp_path: Path) -> None:
    spec = validate(tiny_search(score_epochs=[1, 3]))
    fake = search.Part("tiny_search", "", spec, pd.DataFrame(), tmp_path)
    with pytest.raises(ValueError, match="score_epochs must be 1 <= FIRST <= LAST <= 2, got 1 3"):
        search.score_window(fake)


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


def test_a_tiny_search_runs_every_point_ranks_them_and_resumes(tmp_path: Path, capsys) -> None:
    run_study(tiny_search(), tmp_path, "serial")
    text = capsys.readouterr().out
    results = search.rank(find_parts(tmp_path, "tiny_search")[0])
    assert sorted(r["n_epochs"] for r in results) == [1, 2]
    scores = [r["reward_per_step"] for r in results]
    assert all(math.isfinite(v) for v in scores) and scores == sorted(scores, reverse=True)
    assert (tmp_path / "table.md").read_text().strip() in text
    files = sorted((tmp_path / "rows").glob("*.csv"))
    assert [p.name for p in files] == ["n_epochs=1_seed0.csv", "n_epochs=2_seed0.csv"]
    stamps = [p.stat().st_mtime_ns for p in files]
    run_study(tiny_search(), tmp_path, "serial")
    assert [p.stat().st_mtime_ns for p in files] == stamps


def test_a_point_run_again_with_other_settings_is_refused_not_reused(tmp_path: Path) -> None:
    """The defect of the old command: a second run with ``--set ent_coef:0.5 n_envs:4`` reported the first's rows."""
    run_study(tiny_search(), tmp_path, "serial", report=False)
    changed = tiny_search()
    changed["grid"]["override"] = {**changed["grid"]["override"], "ent_coef": 0.5, "n_envs": 4}
    with pytest.raises(ValueError, match=r"arms\.n_epochs=1\.override\.n_envs: 2 != 4") as error:
        run_study(changed, tmp_path, "serial", report=False)
    assert "arms.n_epochs=1.hyperparams.ent_coef: 0.0 != 0.5" in str(error.value)
