"""Every registered Nomad ID's batched env (its ``vector_entry_point``) steps like N single envs, with any option."""

import inspect
from collections.abc import Callable
from dataclasses import fields
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import load_env_creator

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_envs.memorable.database import SensorDatabase
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad.episode import EnvOptions
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_zoo.vec_env import has_batched_env, make_train_env

IDS = [
    "NomadOffice-v0",
    "NomadOfficeReal-v0",
    "NomadOfficeMemorable-v0",
    "NomadOfficeOpen-v0",
    "NomadOfficeRealOpen-v0",
    "NomadOfficeMemorableOpen-v0",
]


@pytest.mark.parametrize("env_id", IDS)
def test_batched_env_equals_single_envs(env_id: str) -> None:
    assert has_batched_env(env_id)
    batched, single = (make_train_env(env_id, 4, seed=3, mode=mode) for mode in ("batched", "dummy"))
    np.testing.assert_array_equal(batched.reset(), single.reset())
    rng, episodes = np.random.default_rng(0), 0
    for _ in range(300):
        actions = rng.integers(0, 4, 4)
        (obs_b, rew_b, done_b, info_b), (obs_s, rew_s, done_s, info_s) = batched.step(actions), single.step(actions)
        np.testing.assert_array_equal(obs_b, obs_s)
        np.testing.assert_array_equal(rew_b, rew_s)
        np.testing.assert_array_equal(done_b, done_s)
        assert [i.get("route") for i in info_b] == [i.get("route") for i in info_s]
        episodes += int(done_b.sum())
    assert episodes > 10  # episodes ended and were reset on both sides


# --- gym.make_vec(..., vectorization_mode="vector_entry_point") takes every option of gym.make -------------------

NOMAD_IDS = sorted(
    env_id for env_id, spec in gym.registry.items() if env_id.startswith("NomadOffice") and spec.vector_entry_point
)


def _database(map_name: str | None) -> SensorDatabase:
    return record_database(1, map=map_name)  # exact readings, one per cell: not the shipped database


# A non-default value of every constructor option of a registered Nomad env (a function of the ID's registered
# map where the value depends on it). A new option needs a value here, so that its vector support is tested.
OPTION_VALUES: dict[str, Callable[[str | None], Any]] = {
    "map": lambda _: "corridor",
    "observe_odometry": lambda _: False,
    "sensor_noise": lambda _: True,
    "step_sd_cm": lambda _: 2.0,
    "slip_sd_cm": lambda _: 1.5,
    "render_mode": lambda _: "rgb_array",
    "observation": lambda _: "cell",
    "model": lambda _: RealisticModel(slip_sd_cm=2.0, sonar_miss_prob=0.2),
    "database": _database,
    "starts": lambda _: "uniform",
    "progress": lambda _: 0.05,
    "max_episode_steps": lambda _: 25,
    "readings": lambda _: "held_out",
}


def _options(env_id: str) -> list[str]:
    """The constructor's keywords: ``map``, :class:`EnvOptions`' fields and its robot factory's keyword-only ones."""
    creator = load_env_creator(gym.spec(env_id).entry_point)
    robot = inspect.signature(creator.robot_factory).parameters.values()
    own = [parameter.name for parameter in robot if parameter.kind is inspect.Parameter.KEYWORD_ONLY]
    return ["map", *(option.name for option in fields(EnvOptions)), *own]


CASES = [(env_id, option) for env_id in NOMAD_IDS for option in _options(env_id)]


def test_every_vector_id_is_covered():
    assert {"NomadOffice-v0", "NomadOfficeMemorable-v0", "NomadOfficeReal-v0"} <= set(NOMAD_IDS)
    assert {option for _, option in CASES} >= {"map", "step_sd_cm", "slip_sd_cm", "render_mode", "database"}


@pytest.mark.parametrize(("env_id", "option"), CASES)
def test_make_vec_takes_every_option_of_make(env_id: str, option: str) -> None:
    assert option in OPTION_VALUES, f"{env_id} option {option!r}: add a test value to OPTION_VALUES"
    kwargs = {option: OPTION_VALUES[option](gym.spec(env_id).kwargs.get("map"))}
    try:
        singles = [gym.make(env_id, **kwargs) for _ in range(2)]
    except ValueError as err:  # an option value the ID refuses (observation="cell" off the lattice) ...
        with pytest.raises(ValueError):  # ... the batch refuses too
            gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", **kwargs)
        assert option in str(err)
        return
    batch = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", **kwargs)
    obs, info = batch.reset(seed=7)
    for i, single in enumerate(singles):
        single_obs, single_info = single.reset(seed=7 + i)
        np.testing.assert_array_equal(obs[i], single_obs)
        assert tuple(info["position_cm"][i]) == single_info["position_cm"]
    rng = np.random.default_rng(1)
    for t in range(40):
        actions = rng.integers(0, 4, 2)
        obs, rewards, terminated, truncated, info = batch.step(actions)
        for i, single in enumerate(singles):
            single_obs, reward, term, trunc, single_info = single.step(actions[i])
            final = info["final_obs"][i] if term or trunc else obs[i]
            np.testing.assert_array_equal(final, single_obs, err_msg=f"{env_id} {kwargs} step {t} env {i}")
            assert (rewards[i], terminated[i], truncated[i]) == (reward, term, trunc)
            assert ("route" in info) == ("route" in single_info)
            if "route" in info:
                assert info["route"][i] == single_info["route"]
            if term or trunc:
                single.reset()
            elif option == "render_mode" and t in (5, 25):
                np.testing.assert_array_equal(batch.render()[i], single.render())
