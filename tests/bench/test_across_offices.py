"""The study across offices (results/across_offices): what it is built of (a seed per env, a recorded database made
on demand, the timesteps protocol's derived settings, goal checks and transfer), its report's rules, and its record
(the pre-registration before every row file, the table rebuilt from the committed rows byte for byte)."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import yaml

from twodrl_bench.experiment import Experiment
from twodrl_bench.protocol import protocol_of
from twodrl_bench.reports import Part, find_parts, report_parts
from twodrl_bench.reports.across_offices import comparison, pairs

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "results" / "across_offices"
RULES = {
    "claim": "twoda2c",
    "reference": "a2c",
    "learned_at": 0.8,
    "collisions": "train_events_per_episode",
    "learned_guard": -0.10,
    "reward_margin": 0.005,
}


def test_a_seed_in_env_kwargs_is_each_jobs_own() -> None:
    spec = {
        "name": "t",
        "env": "NomadOffice-v0",
        "env_kwargs": {"map": "generated:S:{seed}", "observe_odometry": True},
        "protocol": {"timesteps": 10, "eval_episodes": 1},
        "seeds": [3, 4],
        "arms": {"a2c": {"algo": "a2c"}},
    }
    jobs = Experiment.from_spec(spec).jobs("/tmp/unused")
    assert [j.env_kwargs for j in jobs] == [
        {"map": "generated:S:3", "observe_odometry": True},
        {"map": "generated:S:4", "observe_odometry": True},
    ]
    assert jobs[0].experiment.env_kwargs["map"] == "generated:S:{seed}"  # the spec as written


def test_a_recorded_database_is_the_stand_in_robots_recording() -> None:
    import gymnasium as gym

    import twodrl_envs  # noqa: F401
    from twodrl_envs.memorable.recording import record_database
    from twodrl_envs.nomad.realistic import RealisticModel

    env = gym.make("NomadOfficeMemorable-v0", map="corridor", database="recorded:2:7")
    expected = record_database(2, map="corridor", model=RealisticModel(), seed=7)
    got = env.unwrapped.robot.database
    assert np.array_equal(got.counts, expected.counts) and np.array_equal(got.readings(), expected.readings())
    for bad in ("recorded:0:7", "recorded:2", "recorded:x:1", "recorded:2:-1"):
        with pytest.raises(ValueError, match="database must be 'recorded:K:SEED'"):
            gym.make("NomadOfficeMemorable-v0", map="corridor", database=bad)


@pytest.mark.parametrize(
    ("protocol", "message"),
    [
        ({"check_every": -1}, "protocol.check_every"),
        ({"check_every": 10, "check_episodes": 0}, "protocol.check_episodes"),
        ({"transfer": {"env": "NomadOfficeReal-v0", "trials": 100, "env_kwargs": "map"}}, "protocol.transfer"),
        ({"transfer": {"env": "NomadOfficeReal-v0", "trials": 5}}, "protocol.transfer.trials"),
    ],
)
def test_bad_protocol_keys_are_named(protocol: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        protocol_of({"timesteps": 100, "eval_episodes": 1, **protocol})


def test_a_timesteps_job_on_a_generated_office_trains_as_the_train_command(tmp_path) -> None:
    """The map's derived settings apply (exploring starts, discount, time limit), the checks and the final
    evaluation start at the map's start, and the transfer trials run the stand-in robot in the job's map."""
    pytest.importorskip("rl_zoo3")
    from twodrl_bench.timesteps import resolve_arm, run_plain_job
    from twodrl_zoo.hyperparams import derived_settings

    protocol = {
        "timesteps": 1280,
        "eval_episodes": 2,
        "events": "collision",
        "check_every": 640,
        "check_episodes": 1,
        "transfer": {"env": "NomadOfficeReal-v0", "trials": 10, "env_kwargs": {"map": "generated:S:{seed}"}},
    }
    arm = {
        "name": "twoda2c",
        "algo": "twoda2c",
        "hyperparams": resolve_arm({"algo": "twoda2c"}, "NomadOffice-v0", protocol),
    }
    kwargs = {"map": "generated:S:{seed}"}
    (row,) = run_plain_job(arm, "NomadOffice-v0", kwargs, protocol, 5, str(tmp_path), ["twodrl_envs"])
    settings = derived_settings("NomadOffice-v0", {"map": "generated:S:5"})
    assert settings is not None
    (config,) = (tmp_path / "zoo" / "twoda2c_seed5").glob("twoda2c/*/NomadOffice-v0/config.yml")
    entry = dict(yaml.load(config.read_text(), Loader=yaml.UnsafeLoader))  # rl-zoo3's record of the entry it read
    assert (
        entry["gamma"] == settings.hyperparams["gamma"] and entry["n_timesteps"] == settings.hyperparams["n_timesteps"]
    )
    assert entry["env_kwargs"] == {"map": "generated:S:5", "starts": "uniform", "max_episode_steps": 300}
    checks = json.loads(row["checks"])
    assert [t for t, _ in checks] == [640]  # at rollout starts (64 envs x 5 steps); none at the budget's end
    assert math.isnan(row["first_goal_at"]) or row["first_goal_at"] in [t for t, _ in checks]
    assert row["n_timesteps"] == 1280 and 0 <= row["train_events_per_episode"] <= 1
    assert row["transfer_env"] == "NomadOfficeReal-v0" and row["transfer_trials"] == 10
    outcomes = row["transfer_success"] + row["transfer_collision"] + row["transfer_timeout"]
    assert outcomes == 10


def _part(name: str, rows: list[dict[str, Any]]) -> Part:
    spec = {"name": f"across_offices/{name}", "env_kwargs": {"map": f"generated:{name}:{{seed}}"}, "rules": RULES}
    return Part(spec["name"], name, spec, pd.DataFrame(rows), Path("."))


def _row(arm: str, seed: int, collisions: float, share: float, first: float, reward: float) -> dict[str, Any]:
    return {
        "arm": arm,
        "seed": seed,
        "n_timesteps": 10**6,
        "train_events_per_episode": collisions,
        "final_success_share": share,
        "first_goal_at": first,
        "final_reward_per_step": reward,
    }


def _verdicts(claim: list[tuple], reference: list[tuple]) -> dict[str, str]:
    rows = [_row("twoda2c", i, *v) for i, v in enumerate(claim)] + [_row("a2c", i, *v) for i, v in enumerate(reference)]
    return comparison(pairs([_part("S", rows)], "twoda2c", "a2c"), RULES)[1]


def test_the_rules_read_the_paired_rows() -> None:
    ref = [(0.20 + 0.01 * i, 1.0, 50_000.0, 0.30) for i in range(10)]
    fewer = [(c - 0.05 - 0.001 * i, s, f, r) for i, (c, s, f, r) in enumerate(ref)]
    assert _verdicts(fewer, ref)["R1"] == "holds: twoda2c collides less"
    assert _verdicts(fewer, ref)["R4"] == "equal within 0.005"
    unlearned = [(c, 0.0 if i < 5 else s, f, r) for i, (c, s, f, r) in enumerate(fewer)]
    assert (
        _verdicts(unlearned, ref)["R1"]
        == "not shown: fewer collisions, but the learned interval reaches below the guard"
    )
    more = [(c + 0.05 + 0.001 * i, s, f, r) for i, (c, s, f, r) in enumerate(ref)]
    assert _verdicts(more, ref)["R1"] == "twoda2c collides more"
    slower = [(c, s, f * (3 + i % 2), r - 0.01) for i, (c, s, f, r) in enumerate(ref)]
    assert _verdicts(slower, ref)["R3"] == "twoda2c slower" and _verdicts(slower, ref)["R4"] == "lower"


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout


def test_the_preregistration_precedes_every_row_file() -> None:
    if not (ROOT / ".git").exists():
        pytest.skip("no git history here")
    rows = sorted(STUDY.glob("*/rows.csv"))
    assert rows, "the study's rows are committed"
    first = _git("log", "--format=%H", "--reverse", "--", "results/across_offices/preregistration.md").split()[0]
    for path in rows:
        for commit in _git("log", "--format=%H", "--", str(path.relative_to(ROOT))).split():
            assert _git("merge-base", "--is-ancestor", first, commit) == "" and commit != first, path


def test_the_table_is_rebuilt_from_the_committed_rows(tmp_path) -> None:
    copy = tmp_path / "across_offices"
    shutil.copytree(STUDY, copy)
    report_parts(find_parts(copy, "across_offices"), tmp_path / "out")
    assert (tmp_path / "out" / "table.md").read_bytes() == (STUDY / "table.md").read_bytes()
