"""The benchmark on public tasks: twodrl_envs.public's split wrappers against the envs' own signals, a smoke run of
every task's spec (both arms), and its report (twodrl_bench.reports.benchmark) against the committed tables."""

from __future__ import annotations

import csv
import json
import math
from importlib import resources
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import yaml

pytest.importorskip("rl_zoo3")
pytest.importorskip("scipy")

import twodrl_envs  # noqa: F401  (registers the IDs)
from sb3_twodrl.common.splitting import split_info
from twodrl_bench.reports.benchmark import report, verdict
from twodrl_bench.timesteps import resolve_arm, run_plain_job

TASKS = ("CliffWalking", "LunarLander", "LavaGap", "CartPole", "Acrobot", "Pendulum")
RESULTS = Path(__file__).parents[2] / "results" / "benchmark"


def load_spec(task: str) -> dict[str, Any]:
    return yaml.safe_load(resources.files("twodrl_bench").joinpath("specs", "benchmark", f"{task}.yml").read_text())


def _check_split(reward: float, info: dict) -> None:
    """The 2D arm's ``(r_R, r_P)`` rebuild the stock arm's scalar reward, and ``r_P >= 0``."""
    (reward_r,), (reward_p,) = split_info(np.array([reward]), [info])
    assert reward_p >= 0 and reward_r - reward_p == pytest.approx(reward)


def test_lunar_lander_split_matches_mo_gymnasium_reward_vector() -> None:
    """Same seed, same actions: the scalar is LunarLander's own; r_P is MO's crash and fuel terms."""
    mo_gym = pytest.importorskip("mo_gymnasium")
    pytest.importorskip("Box2D")
    env, mo_env = gym.make("LunarLanderSplit-v3"), mo_gym.make("mo-lunar-lander-v3")
    rng = np.random.default_rng(0)
    crashes = 0
    for episode in range(3):
        env.reset(seed=episode)
        mo_env.reset(seed=episode)
        done = False
        while not done:
            action = int(rng.integers(4))
            _, reward, terminated, truncated, info = env.step(action)
            _, vector, mo_terminated, _, mo_info = mo_env.step(action)
            assert reward == pytest.approx(mo_info["original_reward"]) and terminated == mo_terminated
            _check_split(float(reward), info)
            if terminated:
                crashed = vector[0] == -100
                crashes += crashed
                assert info["crash"] == crashed and info["punishment"] == (100.0 if crashed else 0.0)
            else:
                assert info["punishment"] == pytest.approx(-0.3 * vector[2] - 0.03 * vector[3])
                assert info["crash"] == 0
            done = terminated or truncated
    assert crashes > 0  # random actions crash: the crash branch was checked


def test_cliff_walking_split_punishes_exactly_the_cliff_and_counts_falls() -> None:
    env, raw = gym.make("CliffWalkingSplit-v1"), gym.make("CliffWalking-v1")
    env.reset(seed=0)
    raw.reset(seed=0)
    falls = steps = 0
    for action in [1, 0, 1, 2, 1, 0, 0, 2, 2] * 12:  # right from the start is the cliff
        steps += 1
        _, reward, terminated, truncated, info = env.step(action)
        _, raw_reward, *_ = raw.step(action)
        assert reward == raw_reward  # the stock arm's reward is CliffWalking's own
        falls += raw_reward == -100
        assert info["punishment"] == (99.0 if raw_reward == -100 else 0.0) and info["cliff_falls"] == falls
        _check_split(float(reward), info)
        if truncated:
            break
    assert falls > 0 and steps == 100 and truncated and not terminated  # the 100-step limit


def test_lava_split_punishes_lava_only() -> None:
    """Walk forward until the episode ends: lava (-1, punishment 1) in some layouts, never elsewhere."""
    pytest.importorskip("minigrid")
    outcomes = set()
    for seed in range(8):
        env, raw = gym.make("LavaGapSplit-v0"), gym.make("MiniGrid-LavaGapS7-v0")
        env.reset(seed=seed)
        raw.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            _, reward, terminated, truncated, info = env.step(2)  # forward
            _, raw_reward, *_ = raw.step(2)
            base = env.unwrapped
            cell = base.grid.get(*base.agent_pos)
            lava = terminated and cell is not None and cell.type == "lava"
            assert info["lava"] == lava and info["punishment"] == float(lava) and reward == raw_reward - lava
            _check_split(float(reward), info)
        outcomes.add(bool(info["lava"]))
    assert True in outcomes  # lava was reached at least once


@pytest.mark.parametrize(
    ("task", "arms"),
    [
        ("CliffWalking", ("a2c", "twoda2c", "twoda2c-sign", "ppo", "twodppo", "twodppo-sign")),
        ("LunarLander", ("a2c", "twoda2c")),
        ("LavaGap", ("ppo", "twodppo")),
        ("Acrobot", ("twoda2c", "twodppo")),
    ],
)
def test_smoke_each_task_spec_trains_and_evaluates_its_arms(tmp_path, task: str, arms: tuple[str, ...]) -> None:
    """A few hundred steps per arm (at least one rollout), one deterministic episode; the row is complete.
    PPO on LunarLander is left out: its entry's rollout alone is 16,384 steps."""
    pytest.importorskip({"LunarLander": "Box2D", "LavaGap": "minigrid"}.get(task, "gymnasium"))
    spec = load_spec(task)
    for arm in arms:
        protocol = {**spec["protocol"], "timesteps": 512, "eval_episodes": 1}
        job_arm = {"name": arm, "algo": spec["arms"][arm]["algo"]}
        job_arm["hyperparams"] = resolve_arm(spec["arms"][arm], spec["env"], protocol)
        (row,) = run_plain_job(job_arm, spec["env"], {}, protocol, 0, str(tmp_path), ["twodrl_envs"])
        assert row["arm"] == arm and row["task"] == task and row["n_timesteps"] == 512
        assert math.isfinite(row["final_return"]) and row["final_events"] >= 0 and row["train_episodes"] >= 0
        assert len(json.loads(row["curve"])) == 20


def test_every_task_spec_names_its_rules() -> None:
    for task in TASKS:
        spec = load_spec(task)
        assert (
            spec["name"] == f"benchmark/{task}" and spec["report"] == "benchmark" and spec["seeds"] == list(range(10))
        )
        assert set(spec["rules"]["compare"]) | set(spec["rules"]["compare"].values()) == set(spec["arms"])
        assert (spec["rules"]["events"] is None) == (spec["protocol"]["events"] is None)


def _committed_rows(task: str) -> list[dict[str, Any]]:
    return list(json.loads((RESULTS / task / "rows.json").read_text()).values())


def test_report_of_the_committed_rows_reproduces_the_committed_tables(tmp_path) -> None:
    """One table over the six tasks: every line of each task's committed ``table.md`` is in it; one figure a task."""
    pytest.importorskip("matplotlib")
    rows = [row for task in TASKS for row in _committed_rows(task)]
    text = report(rows, [load_spec(task) for task in TASKS], tmp_path)
    lines = text.splitlines()
    for task in TASKS:
        committed = (RESULTS / task / "table.md").read_text().splitlines()
        assert [line for line in committed if line not in lines] == [], task
    assert (tmp_path / "table.md").read_text() == text + "\n"
    assert sorted(p.name for p in tmp_path.glob("*.png")) == sorted(f"{task}_curve.png" for task in TASKS)


def test_report_reads_rows_back_from_csv(tmp_path) -> None:
    """Rows as the runner stores them (CSV text, the curve as JSON text) give the same table."""
    rows = _committed_rows("CliffWalking")
    path = tmp_path / "rows.csv"
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows({**row, "curve": json.dumps(row["curve"])} for row in rows)
    with path.open() as f:
        text = report(list(csv.DictReader(f)), load_spec("CliffWalking"), tmp_path / "csv", figures=False)
    assert text == report(rows, load_spec("CliffWalking"), tmp_path / "json", figures=False)


def test_report_refuses_rows_of_another_task_and_incomplete_rules(tmp_path) -> None:
    with pytest.raises(ValueError, match="task 'LunarLander' is none of the specs' tasks"):
        report(_committed_rows("LunarLander"), load_spec("CartPole"), tmp_path, figures=False)
    spec = load_spec("CartPole")
    del spec["rules"]["min_seeds"]
    with pytest.raises(ValueError, match=r"rules lack \['min_seeds'\]"):
        report([], spec, tmp_path, figures=False)


def test_table_pairs_each_2d_arm_with_its_stock_arm(tmp_path) -> None:
    rows = [
        {"task": "CliffWalking", "env": "CliffWalkingSplit-v1", "arm": arm, "seed": s, "n_timesteps": 100}
        | {"final_return": ret + s, "train_events_per_episode": ev, "final_length": 13 + 2 * s, "final_events": 0.0}
        for arm, ret, ev in (("a2c", -20.0, 1.0), ("twoda2c", -15.0, 0.5), ("twoda2c-sign", -30.0, 2.0))
        for s in range(3)
    ]
    text = report(rows, load_spec("CliffWalking"), tmp_path, figures=False)
    assert "| CliffWalking | 100 | a2c | -19.0 [" in text
    assert "| twoda2c | -14.0 [-16.5, -11.5] (n=3) | +5.0 [+2.7, +7.3] |" in text
    assert "| twoda2c-sign |" in text and "-0.500" in text and "no verdict (< 5 seeds)" in text
    assert "| a2c | 1/3 [0.06, 0.79] | 1/3 [0.06, 0.79] | 1/3 [0.06, 0.79] | 0/3 [0.00, 0.56] |" in text


def test_verdict_follows_the_pre_registered_rule() -> None:
    base, up, down = [0.0, 1.0, 2.0, 3.0, 4.0], [10.0, 11.0, 12.0, 13.0, 14.0], [-10.0, -9.0, -8.0, -7.0, -6.0]
    assert verdict(up, base, base, base, 5) == "helps"  # return interval above 0
    assert verdict(base, base, down, base, 5) == "helps"  # fewer events, no loss of return
    assert verdict(down, base, base, base, 5) == "hurts"
    assert verdict(base, base, up, base, 5) == "hurts"  # more events
    assert verdict(up, base, up, base, 5) == "trade-off"  # rules 1 and 2 both hold: more return, more events
    assert verdict(down, base, down, base, 5) == "hurts"  # fewer events at a loss of return: rule 1 needs no loss
    assert verdict(base, base[::-1], base, base, 5) == "no difference shown"
    assert verdict(up, base, [], [], 5) == "helps"  # a task without events
    assert verdict(up[:4], base[:4], [], [], 5).startswith("no verdict (< 5")
    assert verdict(up[:4], base[:4], [], [], 4) == "helps"  # min_seeds is the spec's
    assert np.isfinite(base).all()
