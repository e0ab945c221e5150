"""Interest as the softmax temperature (eq. 2, 9) and the actor's update (eq. 10)."""

import copy
from typing import Any

import numpy as np
import pytest
import torch as th
from gymnasium.wrappers import TimeLimit
from stable_baselines3.common.env_util import make_vec_env

from sb3_twodrl import TwoDimA2C
from tests.helpers.toy_envs import LatticeCorridor
from twodrl_bench.algorithms.variants import VariantTwoDimA2C


def action_probabilities(model: TwoDimA2C, interest: float) -> np.ndarray:
    policy = model.policy
    obs = th.zeros((1, *model.observation_space.shape))
    with th.no_grad():
        latent_pi = policy._actor_latent(obs)
        distribution = policy.tempered_distribution(latent_pi, policy.inverse_temperature(np.array([interest])))
    return distribution.distribution.probs.numpy()[0]


@pytest.fixture
def biased_model() -> TwoDimA2C:
    """A model whose actor strongly prefers action 2, whatever the state."""
    model = VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), interest="paper", preferences="raw", seed=0)
    with th.no_grad():
        model.policy.action_net.bias.copy_(th.tensor([0.0, 0.5, 1.0, 0.2]))
    return model


def test_zero_interest_means_uniform_actions(biased_model: TwoDimA2C) -> None:
    np.testing.assert_allclose(action_probabilities(biased_model, 0.0), 0.25, atol=1e-6)


def test_more_interest_means_more_exploration(biased_model: TwoDimA2C) -> None:
    floor = biased_model.policy.min_temperature
    sharp, mild, flat = (action_probabilities(biased_model, floor * i).max() for i in (1.0, 2.0, 4.0))
    assert sharp > mild > flat > 0.25


def test_floor_stops_interest_from_freezing_the_policy(biased_model: TwoDimA2C) -> None:
    """A collapsing interest is clamped: the policy stays as random as at ``min_temperature``."""
    at_floor = action_probabilities(biased_model, biased_model.policy.min_temperature)
    np.testing.assert_allclose(action_probabilities(biased_model, 1e-9), at_floor, rtol=1e-5)
    assert at_floor.max() < 1.0 - 1e-3


@pytest.mark.parametrize("interest", ["paper", "relative"])
def test_first_action_of_each_episode_is_uniform(interest: str) -> None:
    """Eq. 9's modes: an episode's first step has no transition into it, interest 0: uniform actions."""
    model = VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), n_steps=64, interest=interest, seed=0).learn(64)
    buffer = model.rollout_buffer
    starts = buffer.episode_starts.astype(bool)
    assert starts.any() and (buffer.inverse_temperatures[starts] == 0).all()
    assert (buffer.inverse_temperatures[~starts] > 0).all()


@pytest.mark.parametrize(
    ("actor_update", "independent"), [("log_prob", True), ("tempered", False), ("compensated", False)]
)
def test_which_actor_update_depends_on_the_temperature(actor_update: str, independent: bool) -> None:
    """``"log_prob"``: the gradient flows through the raw preferences (eq. 10 has no temperature), so
    one update is the same whatever temperature the actions were drawn at; ``"tempered"``: the score
    is of the policy that drew them, so it is not."""
    model = VariantTwoDimA2C(
        "MlpPolicy", LatticeCorridor(), temperature=0.2, seed=0, n_steps=16, actor_update=actor_update
    ).learn(16)
    policy_state = copy.deepcopy(model.policy.state_dict())
    optimizer_state = copy.deepcopy(model.policy.optimizer.state_dict())
    updated = []
    for temperature in (0.2, 5.0):
        model.policy.load_state_dict(policy_state)
        model.policy.optimizer.load_state_dict(copy.deepcopy(optimizer_state))
        model.policy.temperature = temperature
        model.rollout_buffer.inverse_temperatures[:] = 1.0 / temperature
        np.random.seed(0)
        model.train()
        updated.append(copy.deepcopy(model.policy.state_dict()))
    assert not th.equal(updated[0]["action_net.weight"], policy_state["action_net.weight"])
    same = all(th.equal(updated[1][name], tensor) for name, tensor in updated[0].items())
    assert same == independent


def outcomes(model: TwoDimA2C, deterministic: bool, episodes: int = 30) -> list[str]:
    test_env = TimeLimit(LatticeCorridor(8, 4), 60)
    ends = []
    for episode in range(episodes):
        obs, _ = test_env.reset(seed=1_000 + episode)
        terminated = truncated = False
        while not (terminated or truncated):
            action, _ = model.predict(obs, deterministic=deterministic)
            obs, _, terminated, truncated, info = test_env.step(action)
        ends.append("goal" if info["is_success"] else "time limit" if truncated else "collision")
    return ends


def lattice_model(**kwargs: Any) -> TwoDimA2C:
    env = make_vec_env(lambda: TimeLimit(LatticeCorridor(8, 4), 60), n_envs=4, seed=0)
    return VariantTwoDimA2C("MlpPolicy", env, gamma=0.9, seed=0, **kwargs).learn(8_000)


def test_paper_floor_run_does_not_freeze() -> None:
    """With the floor, eq. 9 taken literally keeps exploring and finds the goal; no episode reaches the time limit."""
    ends = outcomes(lattice_model(interest="paper", preferences="raw"), deterministic=False)
    assert ends.count("time limit") == 0
    assert ends.count("goal") >= 20


def test_default_run_does_not_freeze() -> None:
    """The default learns the way to the goal (its greedy policy takes it) and its stochastic policy,
    which explores more than the paper mode's at the floor, never wanders to the time limit."""
    model = lattice_model()
    assert outcomes(model, deterministic=False).count("time limit") == 0
    assert outcomes(model, deterministic=True, episodes=1) == ["goal"]


def test_stochastic_predict_uses_the_running_interest(biased_model: TwoDimA2C) -> None:
    obs = np.zeros((2_000, *biased_model.observation_space.shape), dtype=np.float32)
    biased_model.policy.running_interest.fill_(0.0)
    calm_start = np.bincount(biased_model.predict(obs, deterministic=False)[0], minlength=4) / len(obs)
    biased_model.policy.running_interest.fill_(biased_model.policy.min_temperature)
    settled = np.bincount(biased_model.predict(obs, deterministic=False)[0], minlength=4) / len(obs)
    np.testing.assert_allclose(calm_start, 0.25, atol=0.04)
    assert settled.argmax() == 2 and settled[2] > 0.5
    assert (biased_model.predict(obs, deterministic=True)[0] == 2).all()


@pytest.mark.parametrize("squash_output", [False, True])
def test_temperature_scales_the_gsde_noise(squash_output: bool) -> None:
    """gSDE: with the same exploration matrix, the action's deviation from the mean and the std grow by ``T``."""
    model = TwoDimA2C("MlpPolicy", "Pendulum-v1", use_sde=True, policy_kwargs=dict(squash_output=squash_output), seed=0)
    policy = model.policy
    policy.reset_noise(1)
    deviations, stds = [], []
    with th.no_grad():
        latent_pi = policy._actor_latent(th.ones((1, 3)))
        mean = policy.action_net(latent_pi)
        for temperature in (1.0, 3.0):
            distribution = policy.tempered_distribution(latent_pi, np.array([1 / temperature], dtype=np.float32))
            actions = distribution.get_actions()
            deviations.append((th.atanh(actions) if squash_output else actions) - mean)
            stds.append(distribution.distribution.stddev)
    assert deviations[0].abs().min() > 0
    assert th.allclose(deviations[1], 3.0 * deviations[0], rtol=1e-3)
    assert th.allclose(stds[1], 3.0 * stds[0], rtol=1e-5)


@pytest.mark.parametrize("use_sde", [False, True])
def test_a_gaussian_at_interest_zero_takes_the_ceiling(use_sde: bool) -> None:
    """Eq. 9 (``interest="paper"``): an episode's first step (interest 0) is uniform for categorical
    actions; a Gaussian has no uniform limit, so it acts at ``max_temperature``, the most random it
    can be, not at the floor."""
    model = VariantTwoDimA2C("MlpPolicy", "Pendulum-v1", use_sde=use_sde, max_temperature=8.0, interest="paper", seed=0)
    inverse = model.policy.inverse_temperature(np.array([0.0, 2.0, 100.0], dtype=np.float32))
    np.testing.assert_allclose(inverse, [1 / 8.0, 1 / 2.0, 1 / 8.0])
    categorical = VariantTwoDimA2C("MlpPolicy", LatticeCorridor(), max_temperature=8.0, interest="paper", seed=0).policy
    np.testing.assert_allclose(categorical.inverse_temperature(np.array([0.0, 2.0], dtype=np.float32)), [0.0, 0.5])
