"""The non-regression check as specs (``non_regression/<env>``): the timesteps job on the packaged settings with a
frozen VecNormalize evaluation, and its report against the committed tables."""

from __future__ import annotations

import json
import math
from importlib import resources
from pathlib import Path
from typing import Any

import pytest
import yaml

pytest.importorskip("rl_zoo3")
pytest.importorskip("scipy")

from sb3_twodrl import TwoDimA2C
from twodrl_bench.reports.non_regression import report
from twodrl_bench.timesteps import resolve_arm, run_plain_job
from twodrl_zoo.hyperparams import hyperparams_path, read_entry

ENVS = ("CartPole-v1", "Acrobot-v1", "Pendulum-v1")
RESULTS = Path(__file__).parents[2] / "results" / "non_regression"


def load_spec(env: str) -> dict[str, Any]:
    return yaml.safe_load(resources.files("twodrl_bench").joinpath("specs", "non_regression", f"{env}.yml").read_text())


@pytest.mark.parametrize("env", ENVS)
def test_specs_train_the_packaged_entries(env: str) -> None:
    spec = load_spec(env)
    assert spec["name"] == f"non_regression/{env}" and spec["env"] == env and spec["report"] == "non_regression"
    for name, arm in spec["arms"].items():
        assert resolve_arm(arm, env, spec["protocol"]) == read_entry(hyperparams_path(arm["algo"]), env), name
    assert spec["rules"]["baseline"] in spec["arms"]


def test_tiny_pendulum_run_evaluates_with_frozen_statistics_and_applies_overrides(tmp_path) -> None:
    spec = load_spec("Pendulum-v1")
    protocol = {**spec["protocol"], "timesteps": 128, "eval_episodes": 1}
    hyperparams = resolve_arm(
        {**spec["arms"]["twoda2c"], "override": {"min_temperature": 1.0}}, "Pendulum-v1", protocol
    )
    arm = {"name": "twoda2c", "algo": "twoda2c", "hyperparams": hyperparams}
    (row,) = run_plain_job(arm, "Pendulum-v1", {}, protocol, 0, str(tmp_path), spec["gym_packages"])
    assert row["arm"] == "twoda2c" and row["task"] == "Pendulum-v1" and math.isfinite(row["final_return"])
    run = tmp_path / "zoo" / "twoda2c_seed0" / "twoda2c" / "Pendulum-v1_1"
    assert (run / "Pendulum-v1" / "vecnormalize.pkl").exists()  # the entry normalises: stats saved and used
    assert TwoDimA2C.load(run / "Pendulum-v1.zip").min_temperature == 1.0  # the override reached rl-zoo3


def _records() -> list[tuple[Path, str]]:
    return [(path, path.parent.name.rsplit("_", 1)[1]) for path in sorted(RESULTS.glob("*/rows.json"))]


@pytest.mark.parametrize(("record", "env"), _records(), ids=[p.parent.name for p, _ in _records()])
def test_report_of_each_committed_record_reproduces_its_table(tmp_path, record: Path, env: str) -> None:
    """The records (``<algo>_seed<seed>`` -> mean return) as rows: the report gives the committed table, exactly."""
    rows = [
        {"task": env, "env": env, "arm": key.rsplit("_seed", 1)[0], "seed": int(key.rsplit("_seed", 1)[1])}
        | {"final_return": value}
        for key, value in json.loads(record.read_text()).items()
    ]
    text = report(rows, load_spec(env), tmp_path)
    assert text + "\n" == (record.parent / "table.md").read_text() == (tmp_path / "table.md").read_text()


def test_report_spans_envs_and_refuses_unknown_rows(tmp_path) -> None:
    rows = [
        {"task": env, "arm": arm, "seed": seed, "final_return": str(0.0 - 10.0 * seed - (arm == "twoda2c"))}
        for env in ("CartPole-v1", "Acrobot-v1")
        for arm in ("twoda2c", "a2c")
        for seed in (1, 0)
    ]
    text = report(rows, [load_spec("CartPole-v1"), load_spec("Acrobot-v1")], tmp_path)
    assert text.count("| a2c | 0.0, -10.0 | -5.0 [") == 2 and text.count("| twoda2c | -1.0, -11.0 |") == 2
    assert text.index("| CartPole-v1 |") < text.index("| Acrobot-v1 |") and "minus a2c" in text
    with pytest.raises(ValueError, match="task 'Acrobot-v1' is none of the specs' tasks"):
        report(rows, load_spec("CartPole-v1"), tmp_path)
