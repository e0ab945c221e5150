"""TwoDimPPO: 2D-RL on SB3's PPO."""

import pytest
import torch as th
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env

from sb3_twodrl import TwoDimPPO
from tests.toy_envs import ScriptedFeedbackEnv

PPO_ARGS = dict(n_steps=32, batch_size=16, n_epochs=4, clip_range_vf=0.2, gae_lambda=0.9, ent_coef=0.01, device="cpu")
DEGENERATE = dict(temperature=1.0, preferences="raw", punishment_weight=0.0, punishment_vf_coef=0.0)


def cartpole(seed: int):
    return make_vec_env("CartPole-v1", n_envs=2, seed=seed)


def test_degenerate_settings_reproduce_ppo_parameters() -> None:
    """10 rollouts of 64 steps, 4 minibatches per epoch, 4 epochs, value clipping on."""
    baseline = PPO("MlpPolicy", cartpole(3), seed=3, **PPO_ARGS).learn(640)
    model = TwoDimPPO("MlpPolicy", cartpole(3), seed=3, **DEGENERATE, **PPO_ARGS).learn(640)
    assert model._n_updates == baseline._n_updates == 40
    actual = model.policy.state_dict()
    for name, tensor in baseline.policy.state_dict().items():
        assert th.allclose(actual[name], tensor, rtol=0, atol=1e-5), name


def test_interest_temperature_changes_the_run() -> None:
    """The equivalence above is not vacuous: the default 2D settings give other parameters."""
    baseline = PPO("MlpPolicy", cartpole(3), seed=3, **PPO_ARGS).learn(128)
    model = TwoDimPPO("MlpPolicy", cartpole(3), seed=3, **PPO_ARGS).learn(128)
    weights = "action_net.weight"
    assert not th.allclose(model.policy.state_dict()[weights], baseline.policy.state_dict()[weights], atol=1e-5)


def head_parameters(model: TwoDimPPO, head: str) -> list[th.Tensor]:
    return [p.detach().clone() for p in getattr(model.policy, head).parameters()]


@pytest.mark.parametrize("clip_range_vf", [None, 0.01])
def test_each_critic_is_clipped_around_its_own_rollout_values(clip_range_vf: float | None) -> None:
    """Both heads moved far from the rollout's values: with clipping neither head gets a gradient, without both."""
    env = ScriptedFeedbackEnv([(1.0, {"punishment": 0.5}), (-1.0, {"punishment": 1.0})])
    args = dict(n_steps=16, batch_size=16, n_epochs=2, clip_range_vf=clip_range_vf, seed=0, device="cpu")
    model = TwoDimPPO("MlpPolicy", env, **args).learn(16)
    model.policy.optimizer.state.clear()  # no Adam momentum from the first update
    before = {}
    for head in ("value_net", "punishment_value_net"):
        with th.no_grad():
            getattr(model.policy, head).bias += 10.0
        before[head] = head_parameters(model, head)
    model.train()
    for head, parameters in before.items():
        unchanged = all(th.equal(a, b) for a, b in zip(parameters, head_parameters(model, head), strict=True))
        assert unchanged == (clip_range_vf is not None), head


def test_logs_ppo_and_2d_keys() -> None:
    model = TwoDimPPO("MlpPolicy", "CartPole-v1", n_steps=16, batch_size=8, n_epochs=1, seed=0).learn(16)
    logged = model.logger.name_to_value
    for key in ("train/clip_fraction", "train/approx_kl", "train/punishment_value_loss", "train/interest"):
        assert key in logged, key
