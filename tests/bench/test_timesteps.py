"""twodrl_bench.timesteps: the job's rows against the rows of the command it replaces, its settings, its input
checks, the Monitor files it reads."""

from __future__ import annotations

import json
import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from tests.helpers.recording_cpu import RECORDING_KERNELS, WHY

pytest.importorskip("rl_zoo3")

from twodrl_bench.settings import settings_file
from twodrl_bench.timestep_measures import learning_curve, training_episodes
from twodrl_bench.timesteps import check_protocol, resolve_arm, run_plain_job

OLD_ROWS = Path(__file__).parents[1] / "data" / "timesteps_old_rows.json"
TASKS = ("CliffWalking", "LunarLander", "LavaGap", "CartPole", "Acrobot", "Pendulum")


def load_spec(name: str) -> dict[str, Any]:
    return yaml.safe_load(resources.files("twodrl_bench").joinpath("specs", f"{name}.yml").read_text())


def _same(a: object, b: object) -> bool:
    """Equal as JSON (NaN, an empty curve bin, equals NaN)."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def _job(spec: dict[str, Any], arm: str, seed: int, out: Path, **protocol: Any) -> dict[str, Any]:
    """The job of (``arm``, ``seed``) as the runner calls it: the arm resolved, ``protocol`` over the spec's."""
    protocol = {**spec["protocol"], **protocol}
    hyperparams = resolve_arm(spec["arms"][arm], spec["env"], protocol)
    job_arm = {"name": arm, "algo": spec["arms"][arm]["algo"], "hyperparams": hyperparams}
    (row,) = run_plain_job(
        job_arm, spec["env"], spec.get("env_kwargs") or {}, protocol, seed, str(out), spec["gym_packages"]
    )
    return row


@pytest.mark.parametrize(
    "spec_name",
    [
        "benchmark/CliffWalking",
        pytest.param("benchmark/Pendulum", marks=pytest.mark.skipif(not RECORDING_KERNELS, reason=WHY)),
    ],
)
def test_rows_equal_the_rows_of_the_command_it_replaces(tmp_path, spec_name: str) -> None:
    """The fixture holds rows that commit 01db862's benchmark command made on this machine (its
    ``made_by``): the job gives the same rows from the spec, ``wall_s`` aside, bit for bit. CliffWalking covers
    the info split and its Monitor events; Pendulum the frozen ``VecNormalize`` statistics of the evaluation. The
    rows have two columns more since (the evaluation's goal share and reward per step)."""
    cases = [c for c in json.loads(OLD_ROWS.read_text())["cases"] if c["spec"] == spec_name]
    assert len(cases) >= 2
    spec = load_spec(spec_name)
    for case in cases:
        old = case["row"]
        row = _job(
            spec, old["arm"], old["seed"], tmp_path, timesteps=case["timesteps"], eval_episodes=case["eval_episodes"]
        )
        assert row.pop("wall_s") >= 0
        row["curve"] = json.loads(row["curve"])
        assert set(row) - set(old) == {"final_success_share", "final_reward_per_step"}
        assert _same({key: row[key] for key in old}, old), (old["arm"], old["seed"])


def test_a_rerun_over_an_interrupted_attempt_gives_the_uninterrupted_row(tmp_path) -> None:
    spec = load_spec("benchmark/CliffWalking")
    row = _job(spec, "twoda2c", 0, tmp_path, timesteps=800, eval_episodes=1)
    logs = tmp_path / "zoo" / "twoda2c_seed0"
    model = next(logs.glob("twoda2c/*/CliffWalkingSplit-v1.zip"))
    (logs / "twoda2c" / "CliffWalkingSplit-v1_2").mkdir()  # a killed attempt's half-written run
    model.write_bytes(b"truncated")
    again = _job(spec, "twoda2c", 0, tmp_path, timesteps=800, eval_episodes=1)
    assert _same({**again, "wall_s": 0}, {**row, "wall_s": 0})
    assert row["arm"] == "twoda2c" and row["task"] == "CliffWalking" and len(json.loads(row["curve"])) == 20


def test_a_learned_coefficients_arm_row_carries_its_course(tmp_path) -> None:
    """An automatic arm's row holds its final model's ``ent_coef_course``, ending at the budget; a stock arm's none."""
    spec = load_spec("auto_entropy/CliffWalking")
    auto = _job(spec, "a2c_auto0.5", 400, tmp_path, timesteps=800, eval_episodes=1)
    course = json.loads(auto["ent_coef_course"])
    assert len(course) == 10 and course[-1][0] == 800 and all(point is not None for point in course)
    assert "ent_coef_course" not in _job(spec, "a2c_ent0", 400, tmp_path, timesteps=800, eval_episodes=1)


def test_env_kwargs_reach_training_and_evaluation(tmp_path) -> None:
    """CartPole's Sutton-Barto reward is 0 a step and -1 at the fall: no return above 0 anywhere."""
    spec = load_spec("benchmark/CartPole")
    spec["env_kwargs"] = {"sutton_barto_reward": True}
    row = _job(spec, "a2c", 0, tmp_path, timesteps=256, eval_episodes=2)
    assert row["final_return"] <= 0 and row["train_return"] <= 0 and row["train_episodes"] > 0
    plain = _job(load_spec("benchmark/CartPole"), "a2c", 0, tmp_path / "plain", timesteps=256, eval_episodes=2)
    assert plain["final_return"] > 0


@pytest.mark.parametrize("task", TASKS)
def test_spec_entries_are_the_settings_the_committed_rows_ran_with(task: str) -> None:
    """``results/benchmark/<task>/settings.json`` recorded each arm's rl-zoo3 entry (the budget in the entry);
    the spec resolves to the same entries (its budget in ``protocol.timesteps``) and evaluation episodes."""
    spec = load_spec(f"benchmark/{task}")
    recorded = json.loads((Path(__file__).parents[2] / "results" / "benchmark" / task / "settings.json").read_text())
    for arm, settings in recorded.items():
        kept = json.loads(settings)
        entry = resolve_arm(spec["arms"][arm], spec["env"], spec["protocol"])
        if spec["protocol"]["timesteps"] is not None:
            entry["n_timesteps"] = spec["protocol"]["timesteps"]
        assert entry == kept["entry"] and kept["n_timesteps"] is None, arm
        assert spec["protocol"]["eval_episodes"] == kept["episodes"]
    assert set(recorded) <= set(spec["arms"])


def test_settings_sources_and_a_rescaled_info_split() -> None:
    lava = load_spec("benchmark/LavaGap")
    assert (
        settings_file("twodppo", lava["arms"]["twodppo"].get("settings", "packaged")).parent.parent.name == "rl_zoo3"
    )  # the stock algo's file
    assert settings_file("twodppo", lava["arms"]["twodppo"].get("settings", "packaged")).name == "ppo.yml"
    assert settings_file("twoda2c").parent.name == "hyperparams"  # packaged
    rescaled = {"algo": "twodppo", "settings": "rl-zoo3", "override": {"reward_split": "info"}}
    with pytest.raises(ValueError, match="normalises rewards"):
        resolve_arm(rescaled, lava["env"], lava["protocol"])
    with pytest.raises(ValueError, match="no entry for 'Breakout-v5'"):
        resolve_arm({"algo": "a2c"}, "Breakout-v5", {"timesteps": None, "eval_episodes": 1})
    with pytest.raises(ValueError, match="arm must be a mapping"):
        resolve_arm({"override": {}}, "CartPole-v1", {})


def test_folder_settings_are_read(tmp_path) -> None:
    (tmp_path / "a2c.yml").write_text("CartPole-v1:\n  n_envs: 2\n  n_timesteps: 100\n  policy: MlpPolicy\n")
    arm = {"algo": "a2c", "settings": str(tmp_path), "override": {"ent_coef": 0.5}}
    assert resolve_arm(arm, "CartPole-v1", {}) == {
        "n_envs": 2,
        "n_timesteps": 100,
        "policy": "MlpPolicy",
        "ent_coef": 0.5,
    }


@pytest.mark.parametrize(
    ("protocol", "match"),
    [
        ({"timesteps": 0, "eval_episodes": 1}, "protocol.timesteps"),
        ({"timesteps": 1.5, "eval_episodes": 1}, "protocol.timesteps"),
        ({"timesteps": None, "eval_episodes": 0}, "protocol.eval_episodes"),
        ({"timesteps": None}, "protocol.eval_episodes"),
        ({"timesteps": None, "eval_episodes": 1, "events": 3}, "protocol.events"),
        ({"timesteps": None, "eval_episodes": 1, "epochs": 3}, r"takes only .* got \['epochs'\]"),
        ({"timesteps": None, "eval_episodes": 1, "keep_learned": True}, "keep_learned needs protocol.check_every"),
        ({"timesteps": None, "eval_episodes": 1, "check_every": 9, "keep_learned": 1}, "protocol.keep_learned"),
    ],
)
def test_bad_protocol_names_the_key(protocol: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        check_protocol(protocol)


def test_bad_job_input_is_refused_before_training(tmp_path) -> None:
    protocol = {"timesteps": 64, "eval_episodes": 1}
    entry = resolve_arm({"algo": "a2c"}, "CartPole-v1", protocol)
    with pytest.raises(ValueError, match="seed must be an int >= 0, got -1"):
        run_plain_job(
            {"name": "a", "algo": "a2c", "hyperparams": entry}, "CartPole-v1", {}, protocol, -1, str(tmp_path), []
        )
    with pytest.raises(ValueError, match=r"algo must be one of \[.*\], got 'nope'"):
        run_plain_job(
            {"name": "a", "algo": "nope", "hyperparams": entry}, "CartPole-v1", {}, protocol, 0, str(tmp_path), []
        )
    with pytest.raises(ValueError, match=r"arm must be \{name, algo, hyperparams\}"):
        run_plain_job({"algo": "a2c", "override": {}}, "CartPole-v1", {}, protocol, 0, str(tmp_path), [])
    unresolved = {"name": "a", "algo": "a2c", "hyperparams": entry}  # resolved without the protocol's events
    with pytest.raises(ValueError, match="monitor_kwargs must record 'cliff_falls'"):
        run_plain_job(unresolved, "CartPole-v1", {}, {**protocol, "events": "cliff_falls"}, 0, str(tmp_path), [])
    assert not (tmp_path / "zoo").exists()


def test_monitor_files_become_training_episodes_and_a_curve(tmp_path) -> None:
    for i, lines in enumerate((["-3,2,0.1,1", "-1,4,0.2,0"], ["-5,3,0.1,2"])):
        (tmp_path / f"{i}.monitor.csv").write_text('#{"t_start": 0}\nr,l,t,cliff_falls\n' + "\n".join(lines) + "\n")
    episodes = training_episodes(tmp_path, 2, "cliff_falls")
    assert episodes.tolist() == [[4, -3, 1], [6, -5, 2], [12, -1, 0]]  # ended at (steps of its env) * n_envs
    curve = learning_curve(episodes, 12, bins=2)
    assert curve == [[6.0, -4.0, 1.5], [12.0, -1.0, 0.0]]
    assert math.isnan(learning_curve(episodes, 24, bins=2)[1][1])  # an empty bin
    assert training_episodes(tmp_path, 1, None)[:, 2].tolist() == [0.0, 0.0]  # no events key: none counted
    assert np.array_equal(training_episodes(tmp_path, 2, None)[:, :2], episodes[:, :2])


@pytest.mark.slow
def test_keep_learned_stops_once_learned_and_evaluates_the_kept_policy(tmp_path) -> None:
    """The timesteps protocol with ``keep_learned`` behaves as ``sb3-twodrl-train``: checks from the map's start,
    the best check's policy kept, training stopped once learned, the final evaluation of the kept policy."""
    pytest.importorskip("rl_zoo3")
    protocol = {"timesteps": 2_000_000, "eval_episodes": 2, "check_every": 25_600, "check_episodes": 1}
    protocol["keep_learned"] = True
    arm = {"name": "twoda2c", "algo": "twoda2c"}
    arm["hyperparams"] = resolve_arm(arm, "NomadOffice-v0", protocol)
    (row,) = run_plain_job(arm, "NomadOffice-v0", {"map": "generated:S:3"}, protocol, 0, str(tmp_path), ["twodrl_envs"])
    checks = json.loads(row["checks"])
    assert row["learned_at"] == checks[-1][0] < 2_000_000 and checks[-1][1] == checks[-2][1] == 1.0
    assert row["steps"] == row["learned_at"] + 64  # the stop comes at the first step after the rollout's check
    assert row["kept_at"] in [t for t, share in checks if share == 1.0] and row["final_success_share"] == 1.0
