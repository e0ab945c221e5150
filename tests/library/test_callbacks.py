"""Exact values of the navigation metrics on a scripted env with known episodes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from stable_baselines3 import A2C
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import KVWriter, Logger
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_twodrl.callbacks import (
    EpisodeRecord,
    EpisodeTracker,
    NavigationMetricsCallback,
    StopAfterEpisodes,
    summarize_episodes,
)
from tests.helpers.toy_nav import SCRIPT, ToyNavEnv, expected_episode

KEYS = ["goal_rate", "reward_per_step", "shortcut_share", "detour_share", "collision_rate"]


class Capture(KVWriter):
    def __init__(self):
        self.dumps: list[dict] = []

    def write(self, key_values, key_excluded, step=0):
        self.dumps.append(dict(key_values))

    def close(self):
        pass


def expected(specs):
    ratios = [expected_episode(s)[0] / s[0] for s in specs]
    labelled = [s[1] for s in specs if s[1] is not None]
    return {
        "goal_rate": np.mean([s[2] == "goal" for s in specs]),
        "reward_per_step": np.mean(ratios),
        "shortcut_share": labelled.count("shortcut") / len(labelled) if labelled else math.nan,
        "detour_share": labelled.count("detour") / len(labelled) if labelled else math.nan,
        "collision_rate": np.mean([s[2] == "collision" for s in specs]),
    }


def test_full_script_values_by_hand():
    # 5 episodes: 2 goals, 2 collisions, 1 timeout; routes labelled: shortcut, detour, shortcut.
    m = expected(SCRIPT)
    assert m["goal_rate"] == pytest.approx(0.4)
    assert m["collision_rate"] == pytest.approx(0.4)
    assert m["shortcut_share"] == pytest.approx(2 / 3)
    assert m["detour_share"] == pytest.approx(1 / 3)
    by_hand = (4.97 / 3 + 4.95 / 5 + (-1.02) / 2 + (-1.04) / 4 + (-0.06) / 6) / 5
    assert m["reward_per_step"] == pytest.approx(by_hand)


@pytest.mark.parametrize("monitored", [True, False])
def test_callback_logs_exact_values_with_a2c(monitored):
    # Two envs, each running the 20-step script once; A2C rollouts of 5 steps x 2 envs.
    env = make_vec_env(ToyNavEnv, n_envs=2, seed=0) if monitored else DummyVecEnv([ToyNavEnv, ToyNavEnv])
    model = A2C("MlpPolicy", env, n_steps=5, seed=0, device="cpu")
    capture = Capture()
    model.set_logger(Logger(folder=None, output_formats=[capture]))
    callback = NavigationMetricsCallback(window=100, routes=["shortcut", "detour"])
    model.learn(total_timesteps=40, callback=callback, log_interval=1)
    assert callback.total_episodes == 10
    # Episodes that end within the first 5, 10, 15, 20 steps of each env: cumulative prefixes of SCRIPT.
    ends = np.cumsum([s[0] for s in SCRIPT])
    assert len(capture.dumps) == 4
    for k, dump in enumerate(capture.dumps):
        done = [s for s, e in zip(SCRIPT, ends, strict=True) if e <= 5 * (k + 1)]
        want = expected(done)
        for key in KEYS:
            got = dump[f"rollout/{key}"]
            if math.isnan(want[key]):
                assert math.isnan(got)
            else:
                assert got == pytest.approx(want[key], abs=1e-6), (k, key)


def test_window_keeps_last_episodes():
    env = DummyVecEnv([ToyNavEnv])
    model = A2C("MlpPolicy", env, n_steps=20, seed=0, device="cpu")
    callback = NavigationMetricsCallback(window=2)
    model.learn(total_timesteps=20, callback=callback)
    # The last two episodes of the script: shortcut collision and an unlabelled timeout.
    m = callback.metrics()
    assert m["episodes"] == 2
    assert m["goal_rate"] == 0.0
    assert m["collision_rate"] == 0.5
    assert m["shortcut_share"] == 1.0
    assert m["detour_share"] == 0.0


def test_no_route_key_means_no_share_and_empty_is_nan():
    assert "shortcut_share" not in summarize_episodes([EpisodeRecord(1.0, 2)])
    assert "goal_rate" not in summarize_episodes([EpisodeRecord(1.0, 2)])
    empty = summarize_episodes([], ["shortcut"])
    assert math.isnan(empty["goal_rate"]) and math.isnan(empty["shortcut_share"])
    unlabelled = summarize_episodes([EpisodeRecord(1.0, 2, route=None, has_route_key=True)], ["shortcut"])
    assert math.isnan(unlabelled["shortcut_share"]) and unlabelled["labelled_episodes"] == 0


def test_tracker_prefers_monitor_episode_info():
    tracker = EpisodeTracker(1)
    out = tracker.step([{"episode": {"r": 3.0, "l": 7}, "is_success": True}], [True], rewards=[100.0])
    assert out[0].episode_return == 3.0 and out[0].length == 7 and out[0].success


def test_stop_after_episodes_counts_all_envs():
    env = DummyVecEnv([ToyNavEnv, ToyNavEnv])
    model = A2C("MlpPolicy", env, n_steps=5, seed=0, device="cpu")
    stop = StopAfterEpisodes(3)
    model.learn(total_timesteps=10_000, callback=stop)
    # Both envs finish their 3-step episode at step 3 (2 episodes), then both finish at step 8: 4 >= 3.
    assert stop.n_episodes == 4
    assert model.num_timesteps == 16


def test_route_shares_are_those_of_the_labels_the_env_sets():
    episodes = [EpisodeRecord(1.0, 2, route=label, has_route_key=True) for label in ["left", "up", "left", None]]
    m = summarize_episodes(episodes)
    assert (m["left_share"], m["up_share"], m["labelled_episodes"]) == (pytest.approx(2 / 3), pytest.approx(1 / 3), 3)
    assert "shortcut_share" not in m
    declared = summarize_episodes(episodes, routes=["right"])
    assert declared["right_share"] == 0.0 and declared["left_share"] == pytest.approx(2 / 3)
    assert math.isnan(summarize_episodes([EpisodeRecord(1.0, 2, has_route_key=True)], ["right"])["right_share"])


@pytest.mark.parametrize("routes", ["shortcut", [1, 2]])
def test_routes_must_be_labels(routes):
    with pytest.raises(TypeError, match="routes must be a sequence of route labels"):
        NavigationMetricsCallback(routes=routes)


def test_callback_logs_a_declared_route_from_the_start_and_another_once_taken():
    model = A2C("MlpPolicy", DummyVecEnv([ToyNavEnv]), n_steps=3, seed=0, device="cpu")
    capture = Capture()
    model.set_logger(Logger(folder=None, output_formats=[capture]))
    model.learn(total_timesteps=9, callback=NavigationMetricsCallback(routes=["shortcut"]), log_interval=1)
    # the script's first episode (3 steps) takes the shortcut, the second (5 steps) the detour
    first, second, third = capture.dumps
    assert first["rollout/shortcut_share"] == second["rollout/shortcut_share"] == 1.0
    assert "rollout/detour_share" not in first and "rollout/detour_share" not in second
    assert third["rollout/shortcut_share"] == third["rollout/detour_share"] == 0.5
