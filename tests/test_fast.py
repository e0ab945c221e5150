"""The fast path (sb3_twodrl.common.fast, .infos) gives stock SB3's numbers bit for bit."""

import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C, PPO

import envs  # noqa: F401  (registers the Nomad ids)
from sb3_twodrl.callbacks import EpisodeTracker
from sb3_twodrl.common.infos import BatchInfos
from twodrl_bench.baselines import BatchedA2C, BatchedPPO
from twodrl_bench.vec_env import make_train_env

PPO_ARGS = dict(n_steps=64, batch_size=32, n_epochs=2)


def _assert_same_parameters(expected: th.nn.Module, actual: th.nn.Module) -> None:
    actual_state = actual.state_dict()
    for name, tensor in expected.state_dict().items():
        assert th.equal(actual_state[name], tensor), name


@pytest.mark.parametrize(
    "stock, fast, env_id, kwargs",
    [
        (A2C, BatchedA2C, "CartPole-v1", {}),
        (A2C, BatchedA2C, "Pendulum-v1", {}),  # Box actions: SB3's own forward
        (PPO, BatchedPPO, "CartPole-v1", PPO_ARGS),
    ],
)
def test_fast_stock_algorithm_learns_sb3s_parameters_bitwise(stock, fast, env_id, kwargs) -> None:
    expected = stock("MlpPolicy", env_id, seed=4, device="cpu", **kwargs).learn(400)
    actual = fast("MlpPolicy", env_id, seed=4, device="cpu", **kwargs).learn(400)
    _assert_same_parameters(expected.policy, actual.policy)
    obs = np.stack([actual.env.observation_space.sample() for _ in range(7)])
    assert np.array_equal(expected.predict(obs, deterministic=True)[0], actual.predict(obs, deterministic=True)[0])


def test_fast_a2c_on_the_batched_office_matches_sb3_bitwise() -> None:
    """Lazy infos, the info buffer restricted to finished episodes, the forward pass: nothing changes a number."""
    models = []
    for algo in (A2C, BatchedA2C):
        env = make_train_env("NomadOffice-v0", 16, seed=2)
        models.append(algo("MlpPolicy", env, n_steps=5, seed=2, device="cpu").learn(4000))
    _assert_same_parameters(models[0].policy, models[1].policy)
    assert list(models[0].ep_success_buffer) == list(models[1].ep_success_buffer)
    assert len(models[1].ep_success_buffer) > 0


def test_hooked_layer_is_called_as_a_module() -> None:
    model = BatchedA2C("MlpPolicy", "CartPole-v1", seed=0, device="cpu")
    calls = []
    model.policy.mlp_extractor.policy_net[0].register_forward_hook(lambda *args: calls.append(1))
    model.policy(th.zeros(3, 4))
    assert calls == [1]


def _batch() -> BatchInfos:
    columns = {"a": np.array([1.0, 2.0, 3.0]), "xy": np.arange(6).reshape(3, 2), "name": np.array(["u", None, "w"])}
    return BatchInfos(3, columns, {"a": np.array([True, False, True])})


def test_batch_infos_are_the_per_env_dicts() -> None:
    infos = _batch()
    expected = [
        {"a": 1.0, "xy": [0, 1], "name": "u"},
        {"xy": [2, 3], "name": None},
        {"a": 3.0, "xy": [4, 5], "name": "w"},
    ]
    assert infos == expected and list(infos) == expected
    assert infos[-1] == expected[2] and infos[1:] == expected[1:]
    with pytest.raises(IndexError):
        infos[3]
    assert infos.column("a") is None  # env 1 has no "a"
    assert infos.column("xy") is not None
    np.testing.assert_array_equal(infos.indices_with("a"), [0, 2])


def test_batch_infos_keep_changes_and_columns_follow_them() -> None:
    infos = _batch()
    infos[0]["xy"] = "changed"
    infos[2]["extra"] = True
    assert infos[0]["xy"] == "changed" and infos[2]["extra"] is True
    assert infos.column("xy") is None  # a changed dict is read as it is
    np.testing.assert_array_equal(infos.indices_with("extra"), [2])


def test_episode_tracker_reads_batch_columns_as_the_dicts() -> None:
    venv = make_train_env("NomadOffice-v0", 8, seed=1)
    by_columns, by_dicts = EpisodeTracker(8), EpisodeTracker(8)
    rng = np.random.default_rng(0)
    venv.reset()
    records = ([], [])
    for _ in range(300):
        _, rewards, dones, infos = venv.step(rng.integers(0, 4, 8))
        assert isinstance(infos, BatchInfos)
        records[0].extend(by_columns.step(infos, dones, rewards))
        records[1].extend(by_dicts.step([dict(info) for info in infos], dones, rewards))
    assert records[0] == records[1] and len(records[0]) > 10
