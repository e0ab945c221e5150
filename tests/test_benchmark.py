"""twodrl_bench.benchmark and envs.public: the split wrappers against the envs' own signals, a smoke
run per task (both arms), the resume after a kill, bad input."""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("rl_zoo3")
pytest.importorskip("scipy")

import envs  # noqa: F401  (registers the IDs)
from sb3_twodrl.common.splitting import split_info
from twodrl_bench.benchmark import (
    TASKS,
    benchmark,
    learning_curve,
    parse_args,
    table,
    train_and_evaluate,
    training_episodes,
    verdict,
    zoo_entry,
)


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


def test_monitor_files_become_training_episodes_and_a_curve(tmp_path) -> None:
    for i, lines in enumerate((["-3,2,0.1,1", "-1,4,0.2,0"], ["-5,3,0.1,2"])):
        (tmp_path / f"{i}.monitor.csv").write_text('#{"t_start": 0}\nr,l,t,cliff_falls\n' + "\n".join(lines) + "\n")
    episodes = training_episodes(tmp_path, 2, "cliff_falls")
    assert episodes.tolist() == [[4, -3, 1], [6, -5, 2], [12, -1, 0]]  # ended at (steps of its env) * n_envs
    curve = learning_curve(episodes, 12, bins=2)
    assert curve == [[6.0, -4.0, 1.5], [12.0, -1.0, 0.0]]
    assert math.isnan(learning_curve(episodes, 24, bins=2)[1][1])  # an empty bin


@pytest.mark.parametrize(
    ("name", "arms"),
    [
        ("CliffWalking", ("a2c", "twoda2c", "ppo", "twodppo")),
        ("LunarLander", ("a2c", "twoda2c")),
        ("LavaGap", ("ppo", "twodppo")),
    ],
)
def test_smoke_each_task_trains_and_evaluates_both_arms(tmp_path, name: str, arms: tuple[str, ...]) -> None:
    """A few hundred steps per arm (at least one rollout), one deterministic episode; the row is complete."""
    pytest.importorskip({"LunarLander": "Box2D", "LavaGap": "minigrid"}.get(name, "gymnasium"))
    for arm in arms:
        row = train_and_evaluate(name, arm, 0, str(tmp_path), 1, 256)
        assert row["arm"] == arm and row["n_timesteps"] == 256 and math.isfinite(row["final_return"])
        assert len(row["curve"]) == 20 and row["final_events"] >= 0
        assert (tmp_path / f"{arm}_seed0" / "curve.json").exists()


def _same(a: object, b: object) -> bool:
    """Equal as JSON (NaN, an empty curve bin, equals NaN)."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_command_resumes_after_a_kill_without_changing_rows(tmp_path) -> None:
    argv = ["--env", "CliffWalking", "--algos", "a2c", "twoda2c", "--seeds", "0", "1", "--n-timesteps", "800"]
    argv += ["--episodes", "1", "--out", str(tmp_path / "a"), "--workers", "0"]
    rows = benchmark(argv)
    out = tmp_path / "a" / "CliffWalking"
    assert [(r["arm"], r["seed"]) for r in rows] == [("a2c", 0), ("a2c", 1), ("twoda2c", 0), ("twoda2c", 1)]
    assert "twoda2c" in (out / "table.md").read_text() and (out / "curve.png").exists()
    kept = (out / "rows.json").read_text()
    model = out / "runs" / "a2c_seed0" / "a2c" / "CliffWalkingSplit-v1_1" / "CliffWalkingSplit-v1.zip"
    stamp = model.stat().st_mtime_ns
    assert (
        _same(benchmark(argv), rows) and (out / "rows.json").read_text() == kept and model.stat().st_mtime_ns == stamp
    )
    # a kill during twoda2c seed 1: its row not written, its logs half written
    stored = json.loads(kept)
    killed = stored.pop("twoda2c_seed1")
    (out / "rows.json").write_text(json.dumps(stored))
    shutil.rmtree(out / "runs" / "twoda2c_seed1" / "twoda2c")
    (out / "runs" / "twoda2c_seed1" / "twoda2c" / "CliffWalkingSplit-v1_1").mkdir(parents=True)
    again = benchmark(argv)
    assert _same(again[:3], rows[:3])  # kept rows unchanged, not recomputed
    assert _same({**again[3], "wall_s": 0}, {**killed, "wall_s": 0})  # the rerun gives the uninterrupted row
    assert model.stat().st_mtime_ns == stamp


def test_kept_rows_of_other_settings_are_refused(tmp_path) -> None:
    argv = ["--env", "CliffWalking", "--algos", "a2c", "--seeds", "0", "1", "--out", str(tmp_path)]
    (tmp_path / "CliffWalking").mkdir()
    (tmp_path / "CliffWalking" / "settings.json").write_text(json.dumps({"a2c": "other"}))
    with pytest.raises(ValueError, match="results of a2c with other settings"):
        benchmark(argv)


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--env", "Breakout"], "env must be one of"),
        (["--env", "LavaGap", "--algos", "a2c"], "algos: 'a2c' is not an arm"),
        (["--env", "LunarLander", "--algos", "twoda2c-sign"], "algos: 'twoda2c-sign'"),
        (["--env", "CliffWalking", "--seeds", "0"], "seeds"),
        (["--env", "CliffWalking", "--episodes", "0"], "episodes"),
        (["--env", "CliffWalking", "--n-timesteps", "0"], "n_timesteps"),
    ],
)
def test_bad_input_names_the_argument(argv: list[str], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        parse_args(argv)


def test_entries_share_the_stock_settings_and_refuse_a_rescaled_info_split() -> None:
    spec = TASKS["LunarLander"]
    stock, two_dim = zoo_entry(spec, "a2c"), zoo_entry(spec, "twoda2c")
    assert two_dim == {**stock, "reward_split": "info", "punishment_gamma": 0.1}
    assert stock["n_timesteps"] == 2e5 and stock["monitor_kwargs"] == "dict(info_keywords=('crash',))"
    assert zoo_entry(TASKS["CliffWalking"], "twoda2c-sign")["reward_split"] == "sign"
    assert zoo_entry(TASKS["LavaGap"], "twodppo")["normalize"] == "{'norm_obs': True, 'norm_reward': False}"
    rescaled = TASKS["LavaGap"].__class__(**{**vars(TASKS["LavaGap"]), "overrides": {}})
    with pytest.raises(ValueError, match="normalises rewards"):
        zoo_entry(rescaled, "twodppo")


def test_table_pairs_each_2d_arm_with_its_stock_arm() -> None:
    rows = [
        {"arm": arm, "seed": s, "final_return": ret + s, "train_events_per_episode": ev, "n_timesteps": 100}
        | {"final_length": 13 + 2 * s, "final_events": 0.0}
        for arm, ret, ev in (("a2c", -20.0, 1.0), ("twoda2c", -15.0, 0.5), ("twoda2c-sign", -30.0, 2.0))
        for s in range(3)
    ]
    text = table("CliffWalking", rows)
    assert "| CliffWalking | 100 | a2c | -19.0 [" in text
    assert "| twoda2c | -14.0 [-16.5, -11.5] (n=3) | +5.0 [+2.7, +7.3] |" in text
    assert "| twoda2c-sign |" in text and "-0.500" in text
    assert "| a2c | 1/3 [0.06, 0.79] | 1/3 [0.06, 0.79] | 1/3 [0.06, 0.79] | 0/3 [0.00, 0.56] |" in text


def test_verdict_follows_the_pre_registered_rule() -> None:
    base, up, down = [0.0, 1.0, 2.0, 3.0, 4.0], [10.0, 11.0, 12.0, 13.0, 14.0], [-10.0, -9.0, -8.0, -7.0, -6.0]
    assert verdict(up, base, base, base) == "helps"  # return interval above 0
    assert verdict(base, base, down, base) == "helps"  # fewer events, no loss of return
    assert verdict(down, base, base, base) == "hurts"
    assert verdict(base, base, up, base) == "hurts"  # more events
    assert verdict(up, base, up, base) == "trade-off"  # rules 1 and 2 both hold: more return, more events
    assert verdict(down, base, down, base) == "hurts"  # fewer events at a loss of return: rule 1 needs no loss
    assert verdict(base, base[::-1], base, base) == "no difference shown"
    assert verdict(up, base, [], []) == "helps"  # a task without events
    assert verdict(up[:4], base[:4], [], []).startswith("no verdict")


@pytest.mark.slow
def test_command_killed_for_real_resumes_to_the_rows_of_an_uninterrupted_run(tmp_path) -> None:
    """SIGKILL the command (its own process group) after its first row; run it again; compare with a clean run."""
    argv = ["--env", "CliffWalking", "--algos", "a2c", "twoda2c", "--seeds", "0", "1", "--n-timesteps", "800"]
    argv += ["--episodes", "1", "--workers", "0", "--no-figure"]
    clean = benchmark([*argv, "--out", str(tmp_path / "clean")])
    store = tmp_path / "killed" / "CliffWalking" / "rows.json"
    command = [sys.executable, "scripts/benchmark.py", *argv, "--out", str(tmp_path / "killed")]
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1]), "OMP_NUM_THREADS": "1"}
    proc = subprocess.Popen(command, cwd=Path(__file__).resolve().parents[1], env=env, start_new_session=True)
    try:
        while proc.poll() is None and not (store.exists() and json.loads(store.read_text())):
            time.sleep(0.2)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert 1 <= len(json.loads(store.read_text())) < 4  # killed midway
    resumed = benchmark([*argv, "--out", str(tmp_path / "killed")])
    assert _same([{**r, "wall_s": 0} for r in resumed], [{**r, "wall_s": 0} for r in clean])
