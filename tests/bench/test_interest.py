"""The interest modes of ``sb3_twodrl.common.interest``: what each one's temperature means (eq. 2, 9)."""

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from gymnasium.wrappers import TimeLimit
from stable_baselines3.common.env_util import make_vec_env

from sb3_twodrl import TwoDimA2C
from tests.helpers.toy_envs import LatticeCorridor
from twodrl_bench.algorithms.variants import INTEREST_MODES, VariantTwoDimA2C, scored_actions

WEST = 3  # LatticeCorridor's move into the wall at the start


class ScaledFeedback(gym.Wrapper):
    """Multiplies the reward and ``info["punishment"]`` (so ``r_R`` and ``r_P``) by ``factor``."""

    def __init__(self, env: gym.Env, factor: float):
        super().__init__(env)
        self.factor = factor

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        info = {**info, "punishment": self.factor * info["punishment"]}
        return obs, self.factor * reward, terminated, truncated, info


def rollout_temperatures(interest: str, factor: float) -> np.ndarray:
    """Inverse temperatures of one seeded rollout with rewards and critics' outputs scaled by ``factor``."""
    env = make_vec_env(lambda: ScaledFeedback(TimeLimit(LatticeCorridor(5, 3), 40), factor), n_envs=2, seed=0)
    model = VariantTwoDimA2C("MlpPolicy", env, n_steps=64, gamma=0.9, interest=interest, seed=0)
    heads = [model.policy.value_net, model.policy.punishment_value_net]
    if model.policy.interest_net is not None:  # the learned interest's estimate scales with what it predicts
        heads.append(model.policy.interest_net)
    with th.no_grad():  # critics whose every output is `factor` times as large: every TD error scales
        for head in heads:
            head.weight.mul_(factor)
            head.bias.mul_(factor)
    model.learn(128)
    return model.rollout_buffer.inverse_temperatures.copy()


@pytest.mark.parametrize("interest", ["relative", "learned"])
def test_relative_interest_does_not_depend_on_the_reward_scale(interest: str) -> None:
    """Both modes divide by the running mean of ``delta+``: rewards, punishments and every
    estimate ten times as large leave each temperature as it was."""
    base, scaled = rollout_temperatures(interest, 1.0), rollout_temperatures(interest, 10.0)
    tempered = base[base > 0]
    assert np.unique(tempered).size > 10  # the interest, not a clamp, set most temperatures
    np.testing.assert_allclose(scaled, base, rtol=1e-4)


def test_paper_interest_depends_on_the_reward_scale() -> None:
    """The property above is not vacuous: eq. 9 taken literally runs ten times hotter."""
    base, scaled = rollout_temperatures("paper", 1.0), rollout_temperatures("paper", 10.0)
    assert not np.allclose(scaled, base, rtol=1e-2)


def test_learned_interest_head_predicts_delta_plus() -> None:
    """The head's target is the interest of the transition out of each state: repeated updates on
    one rollout bring its predictions close to that rollout's ``delta+``."""
    env = make_vec_env(lambda: TimeLimit(LatticeCorridor(5, 3), 40), n_envs=4, seed=0)
    model = VariantTwoDimA2C("MlpPolicy", env, n_steps=32, gamma=0.9, interest="learned", learning_rate=3e-3, seed=0)
    model.learn(128)
    buffer = model.rollout_buffer
    observations = th.as_tensor(buffer.observations.reshape(-1, *model.observation_space.shape))
    targets = buffer.interests.reshape(-1)  # flattened in the buffer's sample order

    def error() -> float:
        with th.no_grad():
            _, _, _, predicted = model.policy.evaluate_state(observations)
        return float(np.mean((predicted.numpy().ravel() - targets) ** 2))

    baseline = float(np.var(targets))
    before = error()
    for _ in range(300):
        model.train()
    assert error() < 0.5 * min(before, baseline)


def test_learned_interest_head_is_saved_and_loaded(tmp_path: Any) -> None:
    env = make_vec_env(lambda: TimeLimit(LatticeCorridor(5, 3), 40), n_envs=2, seed=0)
    model = TwoDimA2C("MlpPolicy", env, n_steps=16, seed=0).learn(320)
    model.save(tmp_path / "model")
    loaded = TwoDimA2C.load(tmp_path / "model")
    assert loaded.policy.interest_net is not None
    for name, tensor in model.policy.state_dict().items():
        assert th.equal(loaded.policy.state_dict()[name], tensor), name
    obs = np.eye(15, dtype=np.float32)
    with th.no_grad():
        expected = model.policy.get_distribution(th.as_tensor(obs)).distribution.probs
        actual = loaded.policy.get_distribution(th.as_tensor(obs)).distribution.probs
    th.testing.assert_close(actual, expected)
    assert model.policy.running_interest.item() > 0
    assert loaded.policy.running_interest.item() == model.policy.running_interest.item()


def test_only_the_learned_mode_has_an_interest_head() -> None:
    for mode in INTEREST_MODES:
        policy = VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), interest=mode).policy
        assert (policy.interest_net is not None) == (mode == "learned")


def test_a_fixed_temperature_has_no_interest_head() -> None:
    """At a fixed temperature the interest sets nothing: no head, so nothing of it reaches the update
    (its gradient would change the clipped norm), and the fixed-temperature controls are the same
    whatever the interest mode."""
    env = make_vec_env(lambda: TimeLimit(LatticeCorridor(6, 3), 60), n_envs=2, seed=0)
    params = []
    for mode in ("paper", "learned"):
        model = VariantTwoDimA2C("MlpPolicy", env, temperature=0.7, interest=mode, seed=0).learn(200)
        assert model.policy.interest_net is None
        params.append(th.nn.utils.parameters_to_vector(model.policy.parameters()))
    th.testing.assert_close(params[0], params[1])


def collapsed_model(lead: float = 30.0, **kwargs: Any) -> TwoDimA2C:
    """A model whose actor has collapsed onto driving into the wall (raw preference ``lead`` for west)."""
    env = make_vec_env(lambda: TimeLimit(LatticeCorridor(6, 3), 60), n_envs=4, seed=0)
    model = VariantTwoDimA2C("MlpPolicy", env, gamma=0.9, seed=0, **kwargs)
    with th.no_grad():
        model.policy.action_net.bias.copy_(th.tensor([0.0, 0.0, 0.0, lead]))
    return model


@pytest.mark.slow  # three learning runs, 25-30 s each
@pytest.mark.parametrize(
    ("lead", "kwargs", "outcome"),
    [
        (5.0, dict(ent_coef=0.05), "goal"),
        (30.0, dict(ent_coef=0.05), "collision"),
        (30.0, dict(interest="relative", preferences="bounded"), "goal"),
    ],
)
def test_recovery_from_a_collapsed_actor(lead: float, kwargs: dict, outcome: str) -> None:
    """After 20k steps from an actor collapsed onto the wall (``tests/helpers/collapse_probe.py``,
    seed 0), the greedy policy: the default comes back from a moderate lead (5, with the protocol's
    entropy bonus) but not from the hard one (30: the alternatives at ~exp(-60) get no gradient);
    bounded preferences come back from that too."""
    model = collapsed_model(lead, **kwargs).learn(20_000)
    env = TimeLimit(LatticeCorridor(6, 3), 60)
    obs, _ = env.reset(seed=0)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, _, terminated, truncated, info = env.step(int(model.predict(obs, deterministic=True)[0]))
    assert ("goal" if info["is_success"] else "collision" if terminated else "time limit") == outcome


@pytest.mark.parametrize("interest", [1e-9, 1e-3, 1.0, 1e3])
def test_bounded_relative_keeps_every_action_possible_whatever_the_interest(interest: float) -> None:
    """No freeze: however large the preferences grow and however calm the critics, every action
    keeps a probability of at least half a percent (raw eq. 9 gives the others ~exp(-60)); the
    preferred one stays the most probable."""
    model = collapsed_model(interest="relative", preferences="bounded")
    policy = model.policy
    policy.running_interest.fill_(1.0)
    obs = th.as_tensor(np.eye(18, dtype=np.float32))
    inverse = policy.inverse_temperature(np.full(len(obs), interest, dtype=np.float32))
    with th.no_grad():
        probs = policy.tempered_distribution(policy._actor_latent(obs), inverse).distribution.probs
    assert (probs.argmax(dim=1) == WEST).all() and probs.min() > 0.005


def test_paper_mode_freezes_on_a_collapsed_policy() -> None:
    """The property above is not vacuous: eq. 9 taken literally leaves the alternatives ~exp(-60)."""
    policy = collapsed_model(interest="paper", preferences="raw").policy
    obs = th.as_tensor(np.eye(18, dtype=np.float32))
    inverse = policy.inverse_temperature(np.full(len(obs), 1e-3, dtype=np.float32))
    with th.no_grad():
        probs = policy.tempered_distribution(policy._actor_latent(obs), inverse).distribution.probs
    assert probs.min() < 1e-6


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(interest="surprise"), "interest must be one of"),
        (dict(preferences="softmax"), "preferences must be one of"),
        (dict(interest_coef=-1.0), "interest_coef must be finite and >= 0"),
    ],
)
def test_bad_interest_settings_are_rejected(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), **kwargs)


@pytest.mark.parametrize("bound", [0.5, 2.5])
def test_the_preference_bound_is_the_largest_spread_and_is_saved(bound: float, tmp_path) -> None:
    """``preference_bound`` sets the sd over the actions of the bounded preferences; it travels with the model."""
    model = collapsed_model(interest="relative", preferences="bounded", preference_bound=bound)
    obs = th.as_tensor(np.eye(18, dtype=np.float32))
    with th.no_grad():
        dist = model.policy.tempered_distribution(model.policy._actor_latent(obs), np.ones(18, np.float32))
    spread = dist.distribution.logits.std(dim=1, unbiased=False)  # log-probabilities: the logits shifted
    assert th.allclose(spread, th.full_like(spread, bound), atol=1e-4)
    model.save(tmp_path / "m.zip")
    assert VariantTwoDimA2C.load(tmp_path / "m.zip").policy.preference_bound == bound


@pytest.mark.parametrize("bound", [0, -1.0, float("inf")])
def test_a_bad_preference_bound_is_named(bound: float) -> None:
    with pytest.raises(ValueError, match="preference_bound"):
        VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), preferences="bounded", preference_bound=bound)


@pytest.mark.parametrize(("actor_update", "corrected"), [("log_prob", False), ("preference", True)])
def test_eq10_corrects_a_near_certain_crash(actor_update: str, corrected: bool) -> None:
    """Eq. 10 moves the taken action's preference by the utility whatever its probability: one update
    on a rollout of crashes into the wall lowers the crash's preference. The log-probability gradient
    scales it by ``1 - pi`` (~exp(-60) here), so the collapsed actor stays where it is."""
    model = collapsed_model(temperature=0.5, actor_update=actor_update)
    obs = th.as_tensor(model.get_env().reset())  # the start, where every trial crashes
    with th.no_grad():
        before = model.policy.action_net(model.policy._actor_latent(obs))[:, WEST]
    model.learn(model.n_steps * model.n_envs)
    assert model.ep_info_buffer and all(info["l"] == 1 for info in model.ep_info_buffer)  # every trial crashed
    with th.no_grad():
        after = model.policy.action_net(model.policy._actor_latent(obs))[:, WEST]
    if corrected:
        assert (after < before - 1e-3).all()
    else:
        np.testing.assert_allclose(after.numpy(), before.numpy(), atol=1e-5)


@pytest.mark.parametrize("actor_update", ["preference", "tempered", "compensated", "compensated_skip_uniform"])
def test_the_actor_update_is_saved_and_checked(actor_update: str, tmp_path: Any) -> None:
    model = VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), actor_update=actor_update)
    model.save(tmp_path / "m.zip")
    assert VariantTwoDimA2C.load(tmp_path / "m.zip").actor_update == actor_update
    with pytest.raises(ValueError, match="actor_update must be one of"):
        VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), actor_update="preferences")
    with pytest.raises(ValueError, match="actor_update='preference' needs Discrete actions"):
        VariantTwoDimA2C("MlpPolicy", "Pendulum-v1", actor_update="preference")


@pytest.mark.parametrize("actor_update", ["tempered", "compensated"])
@pytest.mark.parametrize("env_id", ["CartPole-v1", "Pendulum-v1"])
def test_the_tempered_update_at_temperature_one_is_the_log_prob_update(env_id: str, actor_update: str) -> None:
    """At ``T = 1`` the tempered policy is the raw one: both actor updates learn the same parameters
    (up to float32 rounding: a Gaussian's std is broadcast over the batch before the sum)."""

    def learned(actor_update: str) -> list[th.Tensor]:
        model = VariantTwoDimA2C("MlpPolicy", env_id, n_steps=8, temperature=1.0, actor_update=actor_update, seed=3)
        model.learn(64)
        return [p.detach().clone() for p in model.policy.parameters()]

    for tempered, raw in zip(learned(actor_update), learned("log_prob"), strict=True):
        th.testing.assert_close(tempered, raw, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("use_sde", [False, True])
def test_for_a_gaussian_the_compensated_update_is_the_tempered_one(use_sde: bool) -> None:
    """``T`` scales a Gaussian's std (gSDE: its noise), whose log-gradient holds no ``1/T``: the two
    updates learn the same parameters at any temperature."""

    def learned(actor_update: str) -> list[th.Tensor]:
        model = VariantTwoDimA2C(
            "MlpPolicy", "Pendulum-v1", n_steps=8, temperature=0.5, use_sde=use_sde, actor_update=actor_update, seed=3
        )
        model.learn(64)
        return [p.detach().clone() for p in model.policy.parameters()]

    for compensated, tempered in zip(learned("compensated"), learned("tempered"), strict=True):
        th.testing.assert_close(compensated, tempered, rtol=0, atol=0)


@pytest.mark.parametrize("score", ["tempered", "compensated"])
@pytest.mark.parametrize("temperature", [0.5, 2.0])
def test_the_tempered_score_is_unbiased_under_the_drawing_distribution(temperature: float, score: str) -> None:
    """On-policy: with the same utility for every action, ``E_{a ~ pi_T}[grad log pi_T(a|s)] = 0``, so
    a constant utility moves no preference. The raw score's mean, ``pi_T - pi_1``, is not 0 at ``T != 1``."""
    policy = collapsed_model().policy
    with th.no_grad():
        policy.action_net.bias.copy_(th.tensor([0.5, -0.5, 1.0, 0.0]))
    obs = th.as_tensor(np.repeat(np.eye(18, dtype=np.float32)[:1], 4, axis=0))
    actions = th.arange(4)
    inverse = th.full((4,), 1.0 / temperature)

    def mean_score_gradient(score: str) -> th.Tensor:
        policy.zero_grad()
        *_, scores, _ = scored_actions(policy, obs, actions, inverse, score)
        with th.no_grad():
            probs = policy.tempered_distribution(policy._actor_latent(obs[:1]), inverse[:1]).distribution.probs[0]
        (probs * scores).sum().backward()
        return policy.action_net.bias.grad.clone()

    assert th.allclose(mean_score_gradient(score), th.zeros(4), atol=1e-6)
    assert mean_score_gradient("log_prob").abs().max() > 1e-2


@pytest.mark.parametrize("inverse_temperature", [0.0, 0.1, 2.0])
def test_the_compensated_score_moves_preferences_by_one_hot_minus_the_drawing_distribution(
    inverse_temperature: float,
) -> None:
    """``T * grad log pi_T(a|s)`` with respect to the preferences is ``1[a] - pi_T(.|s)`` at any ``T``
    (the tempered score's is that over ``T``), and stays finite for uniform actions (``1/T = 0``)."""
    policy = collapsed_model().policy
    with th.no_grad():
        policy.action_net.bias.copy_(th.tensor([0.5, -0.5, 1.0, 0.0]))
    obs = th.as_tensor(np.eye(18, dtype=np.float32)[:1])
    inverse = th.full((1,), inverse_temperature)

    def score_gradient(score: str) -> th.Tensor:
        policy.zero_grad()
        *_, scores, _ = scored_actions(policy, obs, th.tensor([2]), inverse, score)
        scores.sum().backward()
        return policy.action_net.bias.grad.clone()

    with th.no_grad():
        probs = policy.tempered_distribution(policy._actor_latent(obs), inverse).distribution.probs[0]
    th.testing.assert_close(score_gradient("compensated"), th.eye(4)[2] - probs)
    th.testing.assert_close(score_gradient("tempered"), inverse_temperature * (th.eye(4)[2] - probs))


def test_the_skip_uniform_score_is_the_compensated_one_but_for_uniform_moves() -> None:
    """``1/T = 0`` (an episode's first move, drawn uniformly): no update; any other ``T``: the compensated one."""
    policy = collapsed_model().policy
    obs = th.as_tensor(np.repeat(np.eye(18, dtype=np.float32)[:1], 2, axis=0))
    actions, inverse = th.tensor([2, 2]), th.tensor([0.0, 2.0])

    def score_gradient(score: str, sample: int) -> th.Tensor:
        policy.zero_grad()
        *_, scores, entropy = scored_actions(policy, obs, actions, inverse, score)
        (scores[sample] + entropy[sample]).backward()
        return th.cat([p.grad.flatten() for p in policy.parameters() if p.grad is not None])

    assert score_gradient("compensated_skip_uniform", 0).abs().max() == 0
    assert score_gradient("compensated", 0).abs().max() > 0
    th.testing.assert_close(score_gradient("compensated_skip_uniform", 1), score_gradient("compensated", 1))
