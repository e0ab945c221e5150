"""``observation="cell"``: the robot's lattice cell as a ``Discrete`` observation (the paper's tabular state)."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.env_checker import check_env

import twodrl_envs  # noqa: F401  (registers the IDs)
from tests.envs.test_nomad_batched import assert_batched_equals_singles
from twodrl_envs.memorable.env import BatchedNomadOfficeMemorable
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_envs.nomad.core import office_core

LATTICE_IDS = ("NomadOffice-v0", "NomadOfficeMemorable-v0")


@pytest.mark.parametrize("env_id", LATTICE_IDS)
def test_cell_is_the_lattice_index_of_the_position_and_keeps_the_dynamics(env_id):
    """Same seed and actions: the cell env moves exactly like the sensor env, and its observation is the
    index of the robot's cell."""
    cell_env, sensor_env = gym.make(env_id, observation="cell"), gym.make(env_id)
    check_env(cell_env.unwrapped)
    lattice = office_core().lattice
    assert cell_env.observation_space == gym.spaces.Discrete(len(lattice.cells))
    obs, info = cell_env.reset(seed=3)
    sensor_env.reset(seed=3)
    assert obs == lattice.index(info["position_cm"]) == office_core().start_cell
    n_done = 0
    for action in np.random.default_rng(0).integers(4, size=400):
        obs, reward, terminated, truncated, info = cell_env.step(action)
        assert (reward, terminated, truncated, info) == sensor_env.step(action)[1:]
        assert obs == lattice.index(info["position_cm"])
        if terminated or truncated:
            n_done += 1
            cell_env.reset(), sensor_env.reset()
    assert n_done > 5


@pytest.mark.parametrize("batch_class", [BatchedNomadOffice, BatchedNomadOfficeMemorable])
def test_batched_cell_observation_equals_single_envs(batch_class):
    batched = batch_class(4, observation="cell", max_episode_steps=40)
    assert batched.single_observation_space == gym.spaces.Discrete(len(office_core().lattice.cells))
    env_id = "NomadOffice-v0" if batch_class is BatchedNomadOffice else "NomadOfficeMemorable-v0"
    singles = [gym.make(env_id, observation="cell", max_episode_steps=40) for _ in range(4)]
    actions = np.random.default_rng(1).integers(4, size=(150, 4))
    assert assert_batched_equals_singles(batched, singles, 5, actions) > 4


@pytest.mark.parametrize("env_id", [*LATTICE_IDS, "NomadOfficeReal-v0"])
@pytest.mark.parametrize("value", ["pixels", "Cell", None, 1])
def test_unknown_observation_is_value_error(env_id, value):
    with pytest.raises(ValueError, match=f"observation must be one of .*got {value!r}"):
        gym.make(env_id, observation=value)
    with pytest.raises(ValueError, match="observation must be one of"):
        gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", observation=value)


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [("NomadOfficeReal-v0", {}), ("NomadOffice-v0", {"step_sd_cm": 1.0}), ("NomadOffice-v0", {"slip_sd_cm": 1.0})],
)
def test_cell_without_lattice_motion_is_value_error(env_id, kwargs):
    with pytest.raises(ValueError, match="observation='cell' needs a robot that moves on the lattice"):
        gym.make(env_id, observation="cell", **kwargs)


def test_batched_real_env_has_no_cell_observation():
    with pytest.raises(ValueError, match="observation='cell' needs a robot that moves on the lattice"):
        gym.make_vec("NomadOfficeReal-v0", num_envs=2, vectorization_mode="vector_entry_point", observation="cell")


def test_cell_start_off_the_lattice_is_value_error():
    env = gym.make("NomadOffice-v0", observation="cell")
    assert env.reset(options={"position": (70.0, 85.0)})[0] == office_core().lattice.index((70.0, 85.0))
    with pytest.raises(ValueError, match="not a lattice cell, which observation='cell' needs"):
        env.reset(options={"position": (65.0, 85.0)})
