"""The transfer (paper section 3.5): trials of the final policy on another env, counted, reported per setting."""

from __future__ import annotations

import json

import gymnasium as gym
import pytest

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_bench.reports import find_parts, transfer
from twodrl_bench.runner import run_study
from twodrl_bench.spec import load_spec, validate


def tiny_transfer(**protocol) -> dict:
    spec = load_spec("transfer/NomadOffice-v0_sensors_only")
    spec["name"] = "tiny_transfer/sensors_only"
    spec["seeds"] = [0, 1]
    spec["arms"] = {"a2c": {"algo": "a2c", "override": {"n_envs": 2}}}
    spec["protocol"] = {**spec["protocol"], "epochs": 1, "learn_episodes": 2, "test_episodes": 1, **protocol}
    return spec


def test_sensors_only_transfer_counts_every_trial(tmp_path) -> None:
    spec = tiny_transfer(transfer={"env": "NomadOfficeReal-v0", "trials": 12})
    run_study(spec, tmp_path / "tiny_transfer" / "sensors_only", "serial", report=False)
    (part,) = find_parts(tmp_path / "tiny_transfer", "tiny_transfer")
    (row,) = transfer.transfer_rows(part)
    assert row.env_kwargs == {"observe_odometry": False} and row.seeds == [0, 1] and row.trials_per_seed == 12
    for seed in range(2):
        assert row.successes[seed] + row.collisions[seed] + row.timeouts[seed] == 12
        assert 0 <= row.paper_successes[seed] <= min(10, row.successes[seed])
        assert row.shortcut[seed] <= row.successes[seed]
        assert 0.0 <= row.train_env_success[seed] <= 1.0
    text = transfer.report([part], tmp_path / "out")
    assert "Transfer to NomadOfficeReal-v0 {'observe_odometry': False}" in text and "held-out seed 1000003" in text
    assert "| a2c | NomadOffice-v0 |" in text
    assert json.loads((tmp_path / "out" / "transfer.json").read_text())[0]["trials_per_seed"] == 12


def test_sensors_only_envs_drop_the_odometry() -> None:
    full = gym.make("NomadOfficeReal-v0").observation_space.shape[0]
    sensors = gym.make("NomadOfficeReal-v0", observe_odometry=False).observation_space.shape[0]
    assert sensors == full - 2 == 32


@pytest.mark.parametrize(
    ("transfer_key", "message"),
    [
        ({"env": "NomadOfficeReal-v0", "trials": 5}, r"transfer\.trials must be at least the paper's 10"),
        ({"env": "NomadOfficeReal-v0"}, r"transfer must be \{env"),
        ({"env": "NomadOfficeReal-v0", "trials": 60, "seeds": 1}, r"transfer must be \{env"),
    ],
)
def test_a_bad_transfer_is_named(transfer_key, message) -> None:
    with pytest.raises(ValueError, match=message):
        validate(tiny_transfer(transfer=transfer_key))
    with pytest.raises(ValueError, match="save_model must be true with a transfer"):
        validate(tiny_transfer(save_model=False))
