"""BatchedNomadOffice == N single NomadOffice-v0 envs with the same seeds; the single env's fast path == the one
definition of the episode (``twodrl_envs.nomad.episode``); the SB3 adapter."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import VecMonitor

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_zoo.vec_env import VectorEnvAdapter

N_ENVS, STEPS, SEED = 6, 150, 11


def assert_batched_equals_singles(batched, singles, seed, actions) -> int:
    """Reset sub-env ``i`` and ``singles[i]`` with ``seed + i``, step both through the rows of
    ``actions`` and check every observation, reward, flag and info entry; returns the episodes ended."""
    obs, _ = batched.reset(seed=seed)
    single_obs = [env.reset(seed=seed + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(single_obs))
    n_done = 0
    for row in actions:
        obs, rewards, terminated, truncated, info = batched.step(row)
        for i, env in enumerate(singles):
            o, r, te, tr, inf = env.step(int(row[i]))
            assert (r, te, tr) == (rewards[i], terminated[i], truncated[i])
            for key in ("route", "is_success", "punishment", "collision"):
                assert inf[key] == info[key][i], key
            assert inf["position_cm"] == tuple(info["position_cm"][i])
            if te or tr:
                n_done += 1
                np.testing.assert_array_equal(o, info["final_obs"][i])
                o, _ = env.reset()
            np.testing.assert_array_equal(o, obs[i])
    return n_done


@pytest.mark.parametrize(("sensor_noise", "odometry"), [(False, True), (True, True), (True, False)])
def test_batched_equals_single_envs(sensor_noise, odometry):
    kwargs = {"sensor_noise": sensor_noise, "observe_odometry": odometry, "max_episode_steps": 40}
    batched = BatchedNomadOffice(N_ENVS, **kwargs)
    singles = [gym.make("twodrl_envs:NomadOffice-v0", **kwargs) for _ in range(N_ENVS)]
    actions = np.random.default_rng(0).integers(4, size=(STEPS, N_ENVS))
    n_done = assert_batched_equals_singles(batched, singles, SEED, actions)
    assert n_done > N_ENVS  # autoreset was exercised


@pytest.mark.parametrize("seeds", [None, [3, None, 5, None, None, 8]])
def test_a_reset_without_a_seed_continues_each_sub_env_as_a_single_env_does(seeds):
    """After a seeded reset, ``reset()`` (or a seed for some sub-envs only) keeps the others' generators and noise
    keys, as ``env.reset()`` of a single env does: a goal check's episodes (a reset per check) are reproducible."""
    kwargs = {"sensor_noise": True, "max_episode_steps": 40, "starts": "uniform"}
    batched = BatchedNomadOffice(N_ENVS, **kwargs)
    singles = [gym.make("twodrl_envs:NomadOffice-v0", **kwargs) for _ in range(N_ENVS)]
    actions = np.random.default_rng(1).integers(4, size=(30, N_ENVS))
    assert_batched_equals_singles(batched, singles, SEED, actions)
    obs, _ = batched.reset(seed=seeds)
    singles_obs = [env.reset(seed=None if seeds is None else seeds[i])[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(singles_obs))
    for row in actions:
        obs, *_ = batched.step(row)
        for i, env in enumerate(singles):
            o, _, te, tr, _ = env.step(int(row[i]))
            o = env.reset()[0] if te or tr else o
            np.testing.assert_array_equal(o, obs[i])


# --- the single env's Python fast path on the lattice == Episodes' arrays -----------------------------------------

FAST_PATH_ENVS = [
    ("twodrl_envs:NomadOffice-v0", {}),
    ("twodrl_envs:NomadOffice-v0", {"sensor_noise": True}),
    ("twodrl_envs:NomadOffice-v0", {"sensor_noise": True, "observe_odometry": False}),
    ("twodrl_envs:NomadOffice-v0", {"observation": "cell", "starts": "uniform"}),
    ("twodrl_envs:NomadOffice-v0", {"step_sd_cm": 1.0, "starts": "uniform"}),
    ("twodrl_envs:NomadOfficeMemorable-v0", {"starts": "uniform"}),
]


@pytest.mark.parametrize(("env_id", "kwargs"), FAST_PATH_ENVS)
def test_single_env_fast_path_equals_the_one_definition(env_id, kwargs):
    episodes = gym.make(env_id, **kwargs).unwrapped.episodes
    rng = np.random.default_rng(4)
    keys = rng.integers(0, 2**63, size=64, dtype=np.uint64)
    start = episodes.start(keys)
    cells, routes = (np.broadcast_to(values, keys.shape) for values in (start.cells, start.routes))
    positions = np.broadcast_to(start.positions, (*keys.shape, 2))
    for i, key in enumerate(keys.tolist()):
        position, cell, route = episodes.start_one(key)
        np.testing.assert_array_equal(position, positions[i])
        assert (cell, route) == (cells[i], routes[i])
    if not episodes.robot.on_lattice:
        return
    cells = np.flatnonzero(episodes.robot.moves.max(axis=1) >= 0)  # recorded / free cells
    steps = rng.integers(0, 300, size=len(cells))
    keys = rng.integers(0, 2**63, size=len(cells), dtype=np.uint64)
    rows = np.ones(len(cells), dtype=bool)
    centres = episodes.core.lattice.cells[cells]
    observed = episodes.observe(rows, cells, centres, centres, keys, steps)
    for i, (cell, key, step) in enumerate(zip(cells.tolist(), keys.tolist(), steps.tolist(), strict=True)):
        np.testing.assert_array_equal(episodes.observe_one(cell, key, step), observed[i])


def test_sb3_adapter_reports_terminal_observation_and_truncation():
    adapter = VectorEnvAdapter(BatchedNomadOffice(4, max_episode_steps=5))
    adapter.seed(0)
    venv = VecMonitor(adapter)
    obs = venv.reset()
    assert obs.shape == (4, 34) and obs.dtype == np.float32
    for t in range(5):
        obs, _, dones, infos = venv.step(np.full(4, 0 if t % 2 == 0 else 2))
    assert dones.all()
    assert all(info["TimeLimit.truncated"] and "terminal_observation" in info for info in infos)
    assert all("episode" in info and info["route"] is None for info in infos)


def test_batched_bad_arguments():
    with pytest.raises(ValueError, match="num_envs"):
        BatchedNomadOffice(0)
    with pytest.raises(ValueError, match="max_episode_steps"):
        BatchedNomadOffice(2, max_episode_steps=0)
    batched = BatchedNomadOffice(2)
    batched.reset(seed=0)
    with pytest.raises(ValueError, match="actions"):
        batched.step(np.array([0, 4]))
