"""Every registered Nomad ID's batched env (its ``vector_entry_point``) steps like N single envs."""

import numpy as np
import pytest

import envs  # noqa: F401  (registers the IDs)
from twodrl_bench.vec_env import has_batched_env, make_train_env

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
