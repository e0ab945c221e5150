"""The speed layer (sb3_twodrl.common.fast, .utils) changes no number: the 2D-RL algorithms with and without it, and
the bench's stock arms on it against stock SB3, learn the same parameters bit for bit."""

import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C, PPO
from stable_baselines3.common.utils import explained_variance

import sb3_twodrl.common.on_policy as on_policy
import sb3_twodrl.common.policies as policies
import twodrl_envs  # noqa: F401  (registers the Nomad ids)
from sb3_twodrl import TwoDimA2C, TwoDimPPO
from twodrl_bench.algorithms.baselines import FastA2C, FastPPO
from twodrl_zoo.vec_env import make_train_env

PPO_ARGS = dict(n_steps=64, batch_size=32, n_epochs=2)


def _assert_same_parameters(expected: th.nn.Module, actual: th.nn.Module) -> None:
    actual_state = actual.state_dict()
    for name, tensor in expected.state_dict().items():
        assert th.equal(actual_state[name], tensor), name


@pytest.mark.parametrize(
    "stock, fast, env_id, kwargs",
    [
        (A2C, FastA2C, "CartPole-v1", {}),
        (A2C, FastA2C, "Pendulum-v1", {}),  # Box actions: SB3's own forward
        (PPO, FastPPO, "CartPole-v1", PPO_ARGS),
    ],
)
def test_fast_stock_algorithm_learns_sb3s_parameters_bitwise(stock, fast, env_id, kwargs) -> None:
    expected = stock("MlpPolicy", env_id, seed=4, device="cpu", **kwargs).learn(400)
    actual = fast("MlpPolicy", env_id, seed=4, device="cpu", **kwargs).learn(400)
    _assert_same_parameters(expected.policy, actual.policy)
    obs = np.stack([actual.env.observation_space.sample() for _ in range(7)])
    assert np.array_equal(expected.predict(obs, deterministic=True)[0], actual.predict(obs, deterministic=True)[0])


def switch_the_speed_layer_off(monkeypatch: pytest.MonkeyPatch) -> None:
    """SB3's ``CategoricalDistribution``, a per-parameter optimizer and numpy's statistics."""
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
    """The batched env's infos, the forward pass, the optimizer: nothing changes a number."""
    models = []
    for algo in (A2C, FastA2C):
        env = make_train_env("NomadOffice-v0", 16, seed=2)
        models.append(algo("MlpPolicy", env, n_steps=5, seed=2, device="cpu").learn(4000))
    _assert_same_parameters(models[0].policy, models[1].policy)
    assert list(models[0].ep_success_buffer) == list(models[1].ep_success_buffer)
    assert len(models[1].ep_success_buffer) > 0


def test_hooked_layers_are_called_as_modules() -> None:
    calls = []
    for model in (FastA2C("MlpPolicy", "CartPole-v1", seed=0), TwoDimA2C("MlpPolicy", "CartPole-v1", seed=0)):
        model.policy.mlp_extractor.policy_net[0].register_forward_hook(lambda *args: calls.append(1))
        model.policy.mlp_extractor.value_net[0].register_forward_hook(lambda *args: calls.append(2))
        model.predict(np.zeros(4, dtype=np.float32))
        model.policy(th.zeros(3, 4))
    assert calls == [1, 1, 2, 1, 2, 1, 2]
