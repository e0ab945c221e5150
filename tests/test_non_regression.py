"""twodrl_bench.non_regression: rl-zoo3 training, frozen VecNormalize evaluation, table, resume."""

from __future__ import annotations

import json
import math

import pytest

pytest.importorskip("rl_zoo3")
pytest.importorskip("scipy")

from sb3_twodrl import TwoDimA2C
from twodrl_bench.non_regression import check_settings, non_regression, parse_args, settings


@pytest.mark.slow  # spawns rl-zoo3 training processes (about 40 s); CI's wheel check runs the command
def test_tiny_pendulum_check_evaluates_every_seed_and_resumes(tmp_path) -> None:
    argv = ["--env", "Pendulum-v1", "--seeds", "0", "1", "--n-timesteps", "128", "--episodes", "1"]
    argv += ["--out", str(tmp_path), "--workers", "2", "--set", "min_temperature:1.0"]
    returns = non_regression(argv)
    assert sorted(returns) == ["a2c", "twoda2c"]
    assert all(len(v) == 2 and all(math.isfinite(x) and x < 0 for x in v) for v in returns.values())
    run = tmp_path / "Pendulum-v1" / "twoda2c_seed0" / "twoda2c" / "Pendulum-v1_1"
    assert (run / "Pendulum-v1" / "vecnormalize.pkl").exists()  # the entry normalises: stats saved and used
    assert TwoDimA2C.load(run / "Pendulum-v1.zip").min_temperature == 1.0  # --set reached rl-zoo3
    stamp = (run / "Pendulum-v1.zip").stat().st_mtime_ns
    assert non_regression(argv) == returns and (run / "Pendulum-v1.zip").stat().st_mtime_ns == stamp
    stored = json.loads((tmp_path / "Pendulum-v1" / "returns.json").read_text())
    assert stored["twoda2c_seed1"] == returns["twoda2c"][1]
    assert "minus a2c" in (tmp_path / "Pendulum-v1" / "table.md").read_text()


def test_one_seed_is_refused() -> None:
    with pytest.raises(ValueError, match="seeds"):
        parse_args(["--env", "CartPole-v1", "--seeds", "0"])


def test_kept_results_of_other_settings_are_refused(tmp_path) -> None:
    """A changed entry (or budget) would silently mix old returns into the table: refused, naming the algo."""
    (tmp_path / "a2c.yml").write_text("CartPole-v1:\n  n_envs: 8\n")
    (tmp_path / "twoda2c.yml").write_text("CartPole-v1:\n  n_envs: 8\n  interest: 'paper'\n")
    argv = ["--env", "CartPole-v1", "--hyperparams-dir", str(tmp_path)]
    check_settings(tmp_path, settings(parse_args(argv)))
    check_settings(tmp_path, settings(parse_args(argv)))  # the same settings resume
    (tmp_path / "twoda2c.yml").write_text("CartPole-v1:\n  n_envs: 8\n  interest: 'relative'\n")
    with pytest.raises(ValueError, match="results of twoda2c with other settings"):
        check_settings(tmp_path, settings(parse_args(argv)))
    with pytest.raises(ValueError, match="no entry for 'Acrobot-v1'"):
        settings(parse_args(["--env", "Acrobot-v1", "--hyperparams-dir", str(tmp_path)]))


def test_set_changes_only_the_2d_algo_and_is_part_of_the_settings(tmp_path) -> None:
    (tmp_path / "a2c.yml").write_text("CartPole-v1:\n  n_envs: 8\n")
    (tmp_path / "twoda2c.yml").write_text("CartPole-v1:\n  n_envs: 8\n")
    argv = ["--env", "CartPole-v1", "--hyperparams-dir", str(tmp_path)]
    plain = settings(parse_args(argv))
    changed = settings(parse_args([*argv, "--set", "min_temperature:1.0"]))
    assert changed["a2c"] == plain["a2c"] and changed["twoda2c"] != plain["twoda2c"]
