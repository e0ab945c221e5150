"""With its 2D extensions switched off, TwoDimA2C is stock A2C."""

import torch as th
from stable_baselines3 import A2C

from sb3_twodrl import TwoDimA2C

A2C_ARGS = dict(n_steps=5, gamma=0.97, gae_lambda=0.95, ent_coef=0.01, seed=3, device="cpu")


def test_degenerate_settings_reproduce_a2c_parameters() -> None:
    """Fixed temperature 1 on raw preferences (the default bounds them), no punishment stream: A2C."""
    baseline = A2C("MlpPolicy", "CartPole-v1", **A2C_ARGS).learn(600)
    degenerate = dict(temperature=1.0, punishment_weight=0.0, punishment_vf_coef=0.0)
    model = TwoDimA2C("MlpPolicy", "CartPole-v1", **degenerate, **A2C_ARGS).learn(600)
    assert model._n_updates == baseline._n_updates >= 100
    expected = baseline.policy.state_dict()
    actual = model.policy.state_dict()
    for name, tensor in expected.items():
        assert th.allclose(actual[name], tensor, rtol=0, atol=1e-5), name


def test_interest_temperature_changes_the_run() -> None:
    """The equivalence above is not vacuous: the default 2D settings give other parameters."""
    baseline = A2C("MlpPolicy", "CartPole-v1", **A2C_ARGS).learn(600)
    model = TwoDimA2C("MlpPolicy", "CartPole-v1", **A2C_ARGS).learn(600)
    weights = "action_net.weight"
    assert not th.allclose(model.policy.state_dict()[weights], baseline.policy.state_dict()[weights], atol=1e-5)


def test_degenerate_settings_reproduce_a2c_with_gsde() -> None:
    gsde_args = dict(n_steps=8, use_sde=True, sde_sample_freq=4, seed=0, device="cpu")
    baseline = A2C("MlpPolicy", "Pendulum-v1", **gsde_args).learn(1000)
    model = TwoDimA2C(
        "MlpPolicy",
        "Pendulum-v1",
        temperature=1.0,
        punishment_weight=0.0,
        punishment_vf_coef=0.0,
        reward_split="none",  # r_R = r whatever its sign (Pendulum's rewards are negative)
        **gsde_args,
    ).learn(1000)
    assert model._n_updates == baseline._n_updates >= 100
    actual = model.policy.state_dict()
    for name, tensor in baseline.policy.state_dict().items():
        assert th.allclose(actual[name], tensor, rtol=0, atol=1e-5), name
