"""The paper's study (quick_preset, paper_preset/<env>): figures 3-5, the summary, the printed comparison."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest
import yaml

pytest.importorskip("matplotlib")

from tests.helpers.toy_study import toy_settings, toy_spec
from twodrl_bench import algo_class
from twodrl_bench.reports import report_study
from twodrl_bench.runner import run_study

FIGS = ["fig3_goal_rate.png", "fig4_reward_per_step.png", "fig5_route_share.png"]


@pytest.fixture(scope="module")
def toy_paper(tmp_path_factory):
    """A two-part study ``toy_paper/<env>`` of one tiny run folder, copied under a second part name."""
    settings = toy_settings(tmp_path_factory.mktemp("settings"))
    runs = tmp_path_factory.mktemp("runs")
    run_study(toy_spec(settings, name="toy_paper/A"), runs / "toy_paper" / "A", "serial", report=False)
    shutil.copytree(runs / "toy_paper" / "A", runs / "toy_paper" / "B")
    spec = yaml.safe_load((runs / "toy_paper" / "B" / "spec.yml").read_text())
    (runs / "toy_paper" / "B" / "spec.yml").write_text(yaml.safe_dump({**spec, "name": "toy_paper/B"}))
    return runs


def test_the_report_prints_the_end_of_run_comparison_and_writes_figures_per_part(toy_paper, tmp_path, capsys):
    text = report_study("toy_paper", toy_paper, tmp_path)
    assert capsys.readouterr().out.strip() == text.strip()
    assert text.count("reward per step over epochs 3-3, mean ± 95% interval over seeds") == 2
    rows = pd.read_csv(toy_paper / "toy_paper" / "A" / "rows.csv")
    final = rows[rows["epoch"] == 3].groupby("arm")["reward_per_step"].mean()
    assert f"  twoda2c: {final['twoda2c']:.4f} ± " in text and f"  a2c: {final['a2c']:.4f} ± " in text
    assert "twoda2c - a2c: " in text and "(95% Welch)" in text
    for part in ("A", "B"):
        assert str(tmp_path / part / "summary.md") in text
        for fig in FIGS:
            assert (tmp_path / part / fig).stat().st_size > 1000
            assert str(tmp_path / part / fig) in text
        assert (tmp_path / part / "rows.csv").read_text() == (toy_paper / "toy_paper" / part / "rows.csv").read_text()
        assert yaml.safe_load((tmp_path / part / "spec.yml").read_text())["name"] == f"toy_paper/{part}"
    table = (tmp_path / "table.md").read_text()
    assert "## toy_paper/A" in table and "## toy_paper/B" in table and "By the paper's epoch windows" in table


def test_the_models_load_and_act(toy_paper):
    for arm in ("twoda2c", "a2c"):
        model = algo_class(arm).load(toy_paper / "toy_paper" / "A" / "models" / f"{arm}_seed0.zip")
        assert model.predict(model.observation_space.sample())[0] in range(4)


def test_env_kwargs_reach_the_envs_and_are_guarded(tmp_path):
    spec = {
        "name": "odometry",
        "env": "NomadOffice-v0",
        "env_kwargs": {"observe_odometry": False},
        "protocol": {"epochs": 1, "learn_episodes": 2, "test_episodes": 1},
        "seeds": [0],
        "arms": {"a2c": {"algo": "a2c", "override": {"n_envs": 2}}},
        "report": "paper",
    }
    run_study(spec, tmp_path, "serial", report=False)
    model = algo_class("a2c").load(tmp_path / "models" / "a2c_seed0.zip")
    assert model.observation_space.shape == (32,)  # 16 sonar + 16 infrared, no odometry
    with pytest.raises(ValueError, match=r"env_kwargs\.observe_odometry: False != <absent>"):
        run_study({**spec, "env_kwargs": {}}, tmp_path, "serial", report=False)
