"""The speed layer (sb3_twodrl.common.fast, .infos, .utils) changes no number: the 2D-RL algorithms with and without
it, and the bench's stock arms on it against stock SB3, learn the same parameters bit for bit."""

import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C, PPO
from stable_baselines3.common.utils import explained_variance

import sb3_twodrl.common.fast as fast
import sb3_twodrl.common.on_policy as on_policy
import sb3_twodrl.common.policies as policies
import twodrl_envs  # noqa: F401  (registers the Nomad ids)
from sb3_twodrl import TwoDimA2C, TwoDimPPO
from sb3_twodrl.callbacks import EpisodeTracker
from sb3_twodrl.common.infos import BatchInfos
from twodrl_bench.algorithms.baselines import BatchedA2C, BatchedPPO
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


def switch_the_speed_layer_off(monkeypatch: pytest.MonkeyPatch) -> None:
    """SB3's module calls, SB3's ``CategoricalDistribution``, a per-parameter optimizer and numpy's statistics."""
    monkeypatch.setattr(fast, "_plain_extractor", lambda policy: False)
    monkeypatch.setattr(policies, "linear", lambda layer, x: layer(x))
    monkeypatch.setattr(policies.TwoDimPolicyMixin, "_categorical", lambda self: False)
    monkeypatch.setattr(
        policies, "build_optimizer", lambda p, lr: p.optimizer_class(p.parameters(), lr=lr(1), **p.optimizer_kwargs)
    )
    monkeypatch.setattr(on_policy, "fast_mean", lambda x: float(np.mean(x)))
    monkeypatch.setattr(on_policy, "fast_explained_variance", lambda p, t: explained_variance(p.ravel(), t.ravel()))


@pytest.mark.parametrize(
    "algo, env_id, kwargs",
    [(TwoDimA2C, "CartPole-v1", {}), (TwoDimA2C, "Pendulum-v1", {}), (TwoDimPPO, "CartPole-v1", PPO_ARGS)],
)
def test_the_speed_layer_changes_no_number_of_the_2d_algorithms(
    monkeypatch: pytest.MonkeyPatch, algo: type, env_id: str, kwargs: dict
) -> None:
    fast_model = algo("MlpPolicy", env_id, seed=4, device="cpu", **kwargs).learn(400)
    with monkeypatch.context() as patch:
        switch_the_speed_layer_off(patch)
        plain_model = algo("MlpPolicy", env_id, seed=4, device="cpu", **kwargs).learn(400)
        assert not isinstance(plain_model.policy.optimizer.defaults.get("foreach"), bool)
    _assert_same_parameters(plain_model.policy, fast_model.policy)
    np.testing.assert_array_equal(plain_model.rollout_buffer.actions, fast_model.rollout_buffer.actions)


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
