"""TwoDimPPO: 2D-RL on SB3's PPO."""

import numpy as np
import pytest
import torch as th
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env

from sb3_twodrl import TwoDimPPO
from tests.helpers.toy_envs import ScriptedFeedbackEnv
from twodrl_bench.algorithms.variants import VariantTwoDimPPO, scored_actions

PPO_ARGS = dict(n_steps=32, batch_size=16, n_epochs=4, clip_range_vf=0.2, gae_lambda=0.9, ent_coef=0.01, device="cpu")
DEGENERATE = dict(temperature=1.0, punishment_weight=0.0, punishment_vf_coef=0.0)


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


def actor_parameters(model: TwoDimPPO) -> list[th.Tensor]:
    return [
        p.detach().clone()
        for p in (*model.policy.mlp_extractor.policy_net.parameters(), *model.policy.action_net.parameters())
    ]


@pytest.mark.parametrize("actor_update", ["tempered", "compensated", "compensated_skip_uniform"])
def test_tempered_ratios_at_temperature_one_reproduce_the_log_prob_run(actor_update: str) -> None:
    """At a fixed ``T = 1`` the tempered policy is the raw one and no move is uniform: the same parameters."""
    args = dict(temperature=1.0, seed=3, **PPO_ARGS)
    raw = VariantTwoDimPPO("MlpPolicy", cartpole(3), actor_update="log_prob", **args).learn(128)
    tempered = VariantTwoDimPPO("MlpPolicy", cartpole(3), actor_update=actor_update, **args).learn(128)
    for name, tensor in raw.policy.state_dict().items():
        th.testing.assert_close(tempered.policy.state_dict()[name], tensor, rtol=1e-6, atol=1e-7, msg=name)


def rollout_log_ratios(model: TwoDimPPO, actor_update: str) -> th.Tensor:
    """Each stored action's log-ratio under ``actor_update``'s score, with the rollout's policy."""
    data = next(model.rollout_buffer.get(None))
    with th.no_grad():
        *_, log_prob, _ = scored_actions(
            model.policy, data.observations, data.actions.long().flatten(), data.inverse_temperatures, actor_update
        )
    return log_prob - data.old_log_prob


@pytest.mark.parametrize("actor_update", ["log_prob", "tempered", "compensated", "compensated_skip_uniform"])
def test_each_ratio_is_one_before_the_update(actor_update: str) -> None:
    """``old_log_prob`` is stored under the policy the ratio compares: the raw one for ``"log_prob"``,
    the tempered one that drew the actions otherwise; so with ``learning_rate=0`` (the policy stays
    the rollout's) no ratio is clipped and the logged KL is 0, the uniform first moves included."""
    model = VariantTwoDimPPO(
        "MlpPolicy", cartpole(0), learning_rate=0.0, interest="paper", actor_update=actor_update, seed=0, **PPO_ARGS
    )
    with th.no_grad():
        model.policy.action_net.bias.copy_(th.tensor([1.0, -1.0]))  # a policy with preferences to temper
    model.learn(64)
    logged = model.logger.name_to_value
    assert logged["train/clip_fraction"] == 0 and abs(logged["train/approx_kl"]) < 1e-7
    uniform = (model.rollout_buffer.inverse_temperatures == 0).sum()
    assert uniform >= 2  # each env's first move
    other = "tempered" if actor_update == "log_prob" else "log_prob"
    assert rollout_log_ratios(model, other).abs().max() > 1e-3


@pytest.mark.parametrize("actor_update", ["compensated", "compensated_skip_uniform"])
def test_skip_uniform_takes_no_actor_step_from_uniform_moves(actor_update: str) -> None:
    """A rollout drawn wholly uniformly (``1/T = 0``): the skip-uniform ratio gives the actor no
    gradient (the critics still learn); the compensated one moves it."""
    model = VariantTwoDimPPO(
        "MlpPolicy", cartpole(0), learning_rate=0.0, interest="paper", actor_update=actor_update, seed=0, **PPO_ARGS
    )
    model.learn(64)
    buffer = model.rollout_buffer
    buffer.inverse_temperatures[:] = 0.0
    buffer.log_probs[:] = np.log(0.5)  # the uniform policy over CartPole's two actions
    model.lr_schedule = lambda _: 1e-3
    model.policy.optimizer.state.clear()  # no Adam momentum from the rollout's updates at rate 0
    actor, critic = actor_parameters(model), [p.detach().clone() for p in model.policy.value_net.parameters()]
    model.train()
    moved = any(not th.equal(a, b) for a, b in zip(actor, actor_parameters(model), strict=True))
    assert moved == (actor_update == "compensated")
    assert any(not th.equal(a, b) for a, b in zip(critic, model.policy.value_net.parameters(), strict=True))


def test_actor_update_is_validated_and_saved(tmp_path) -> None:
    with pytest.raises(ValueError, match="actor_update must be one of"):
        VariantTwoDimPPO("MlpPolicy", "CartPole-v1", actor_update="preference")
    model = VariantTwoDimPPO("MlpPolicy", "CartPole-v1", n_steps=16, batch_size=8, actor_update="compensated", seed=0)
    model.save(tmp_path / "m.zip")
    assert VariantTwoDimPPO.load(tmp_path / "m.zip").actor_update == "compensated"
