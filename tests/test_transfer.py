"""twodrl_bench.transfer: per-seed outcomes, the paper's 10 trials, sensors-only policies."""

from __future__ import annotations

import json

import gymnasium as gym
import pytest

import envs  # noqa: F401  (registers the IDs)
from twodrl_bench.protocol import parse_env_kwargs
from twodrl_bench.transfer import parse_args, table, transfer


def test_sensors_only_transfer_counts_every_trial(tmp_path) -> None:
    argv = ["--timesteps", "200", "--seeds", "2", "--trials", "12", "--n-envs", "2", "--algos", "a2c"]
    argv += [
        "--train-envs",
        "NomadOffice-v0",
        "--env-kwargs",
        "observe_odometry:False",
        "--json",
        str(tmp_path / "t.json"),
    ]
    (row,) = transfer(parse_args(argv))
    assert row.env_kwargs == {"observe_odometry": False} and row.seeds == [0, 1]
    for seed in range(2):
        assert row.successes[seed] + row.collisions[seed] + row.timeouts[seed] == 12
        assert 0 <= row.paper_successes[seed] <= min(10, row.successes[seed])
        assert row.shortcut[seed] <= row.successes[seed]
    assert json.loads((tmp_path / "t.json").read_text())[0]["trials_per_seed"] == 12
    assert "| a2c | NomadOffice-v0 |" in table([row])


def test_seed_list_overrides_the_seed_count() -> None:
    argv = ["--timesteps", "100", "--seeds", "3", "--seed-list", "7", "--trials", "10", "--n-envs", "2"]
    (row,) = transfer(parse_args([*argv, "--algos", "a2c", "--train-envs", "NomadOffice-v0"]))
    assert row.seeds == [7] and len(row.successes) == 1


def test_sensors_only_envs_drop_the_odometry() -> None:
    full = gym.make("NomadOfficeReal-v0").observation_space.shape[0]
    sensors = gym.make("NomadOfficeReal-v0", observe_odometry=False).observation_space.shape[0]
    assert sensors == full - 2 == 32


@pytest.mark.parametrize("items", [["observe_odometry"], ["observe_odometry:maybe"], ["not a key:1"]])
def test_bad_env_kwargs_are_named(items) -> None:
    with pytest.raises(ValueError, match="key:value"):
        parse_env_kwargs(items)
    assert parse_env_kwargs(["observe_odometry:False", "map:'open'"]) == {"observe_odometry": False, "map": "open"}


def test_fewer_trials_than_the_paper_is_an_error() -> None:
    with pytest.raises(ValueError, match="trials"):
        parse_args(["--trials", "5"])
