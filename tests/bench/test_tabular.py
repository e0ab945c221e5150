"""On the lattice cell (``observation="cell"``) with ``net_arch=[]``, TwoDimA2C is the paper's tabular
2D-RL (eq. 5-10) and A2C the tabular one-step actor-critic, step for step (``docs/tabular.md``).

Each run records the state, the action SB3 drew, the probabilities it drew it from and the
evaluations of every step, and the network's tables after every update; the numpy oracle
(``tests/helpers/tabular_oracle.py``) replays the same actions and must give the same probabilities
before each step and the same tables after it.
"""

import math
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import DummyVecEnv

import twodrl_envs  # noqa: F401  (registers the IDs)
from tests.helpers.tabular_oracle import TabularActorCritic
from twodrl_bench.algorithms.variants import VariantTwoDimA2C
from twodrl_envs.nomad.core import GOAL_REWARD

N_STEPS = 1000
TOLERANCE = 1e-6
LEARNING_RATE = 0.1  # the SGD step: beta = lr, alpha = 2 * vf_coef * lr
VF_COEF = PUNISHMENT_VF_COEF = 0.5  # alpha_R = alpha_P = lr
GAMMA, PUNISHMENT_GAMMA = 0.9, 0.1  # paper section 3.2
MIN_TEMPERATURE, MAX_TEMPERATURE = 0.01, 10.0  # a low floor, so that the interest sets T on most steps
MAX_EPISODE_STEPS = 50  # short episodes, so that the test sees time-limit truncations
TABLE_POLICY: dict[str, Any] = dict(net_arch=[], optimizer_class=th.optim.SGD, optimizer_kwargs={})
RUNS = [("NomadOffice-v0", 0), ("NomadOfficeMemorable-v0", 1)]  # (env, seed)


class ExploringStarts(gym.Wrapper):
    """Each episode starts at a cell drawn uniformly (by the env's seeded RNG) from the recorded free cells,
    so that a run of a thousand steps reaches the goal and the time limit as well as the walls."""

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        self.env.reset(seed=seed)
        base = self.env.unwrapped
        cells = base.core.lattice.cells[np.flatnonzero(base.robot.moves.max(axis=1) >= 0)]  # cells with a free move
        return self.env.reset(options={"position": tuple(cells[base.np_random.integers(len(cells))])})


def cell_env(env_id: str) -> DummyVecEnv:
    return DummyVecEnv(
        [lambda: ExploringStarts(gym.make(env_id, observation="cell", max_episode_steps=MAX_EPISODE_STEPS))]
    )


def tables_without_biases(model: BaseAlgorithm) -> None:
    """Freeze the heads' biases at 0: on one-hot inputs each head is then a table (a bias would be an offset
    that every state shares, updated at every step)."""
    policy = model.policy
    for head in (policy.action_net, policy.value_net, getattr(policy, "punishment_value_net", None)):
        if head is not None:
            head.bias.data.zero_()
            head.bias.requires_grad_(False)


ONE_STEP_SGD = dict(
    learning_rate=LEARNING_RATE,
    n_steps=1,
    gamma=GAMMA,
    gae_lambda=0.0,
    ent_coef=0.0,
    vf_coef=VF_COEF,
    max_grad_norm=math.inf,
    normalize_advantage=False,
    policy_kwargs=TABLE_POLICY,
    device="cpu",
)
"""What both tabular actor-critics share: one-step TD, plain SGD, no clipping, bonus or normalisation."""


def tabular_two_dim_a2c(env: DummyVecEnv, seed: int) -> VariantTwoDimA2C:
    """TwoDimA2C (its variant with eq. 9 and eq. 10 literally) configured as the paper's tabular 2D-RL
    (every setting: docs/tabular.md)."""
    model = VariantTwoDimA2C(
        "MlpPolicy",
        env,
        seed=seed,
        **ONE_STEP_SGD,
        punishment_gamma=PUNISHMENT_GAMMA,
        punishment_gae_lambda=0.0,
        punishment_vf_coef=PUNISHMENT_VF_COEF,
        punishment_weight=1.0,
        reward_split="info",
        temperature="interest",
        min_temperature=MIN_TEMPERATURE,
        max_temperature=MAX_TEMPERATURE,
        interest="paper",
        preferences="raw",
        actor_update="preference",
    )
    tables_without_biases(model)
    return model


def tabular_a2c(env: DummyVecEnv, seed: int) -> A2C:
    """Stock A2C configured as the tabular one-step actor-critic (docs/tabular.md)."""
    model = A2C("MlpPolicy", env, seed=seed, **ONE_STEP_SGD)
    tables_without_biases(model)
    return model


def read_tables(model: BaseAlgorithm) -> tuple[np.ndarray, np.ndarray]:
    """The preference table ``p[s, a]`` and the critic tables ``V_i[s]`` (one row per critic) of the network."""
    policy = model.policy
    heads = [policy.value_net] + ([policy.punishment_value_net] if hasattr(policy, "punishment_value_net") else [])
    with th.no_grad():
        preferences = policy.action_net.weight.T.double().numpy().copy()
        values = np.stack([head.weight[0].double().numpy().copy() for head in heads])
    return preferences, values


class StepRecorder(BaseCallback):
    """Per step: state, action, the probabilities the action was drawn from, ``(r_R, r_P)``, next state,
    terminated, truncated; after each update, the network's tables."""

    def __init__(self, probabilities: Callable[[dict[str, Any], BaseAlgorithm], np.ndarray]) -> None:
        super().__init__()
        self.probabilities = probabilities
        self.steps: list[tuple[Any, ...]] = []
        self.tables: list[tuple[np.ndarray, np.ndarray]] = []

    def _on_rollout_start(self) -> None:
        if self.steps:  # the update of the previous step has been made
            self.tables.append(read_tables(self.model))

    def _on_step(self) -> bool:
        info, done = self.locals["infos"][0], bool(self.locals["dones"][0])
        truncated = done and info.get("TimeLimit.truncated", False)
        next_state = info["terminal_observation"] if done else self.locals["new_obs"][0]
        evaluations = (GOAL_REWARD * info["is_success"], info["punishment"])  # eq. 11-12
        probabilities = self.probabilities(self.locals, self.model)
        state, action = int(self.model._last_obs[0]), int(self.locals["actions"][0])
        self.steps.append(
            (state, action, probabilities, evaluations, int(next_state), done and not truncated, truncated)
        )
        return True

    def _on_training_end(self) -> None:
        self.tables.append(read_tables(self.model))


def drawn_two_dim(local: dict[str, Any], model: BaseAlgorithm) -> np.ndarray:
    """The tempered distribution (eq. 9) TwoDimA2C drew the action from (the parameters have not changed since)."""
    with th.no_grad():
        distribution = model.policy.tempered_distribution(local["latent_pi"], local["inverse_temperature"])
    return distribution.distribution.probs[0].double().numpy()


def drawn_a2c(local: dict[str, Any], model: BaseAlgorithm) -> np.ndarray:
    """A2C's distribution at the state (the parameters have not changed since the action was drawn)."""
    with th.no_grad():
        return model.policy.get_distribution(local["obs_tensor"]).distribution.probs[0].double().numpy()


def replay(oracle: TabularActorCritic, recorder: StepRecorder, two_streams: bool) -> dict[str, float]:
    """Step the oracle through the recorded steps; the largest differences from the network and what was covered."""
    assert len(recorder.steps) == len(recorder.tables) == N_STEPS
    worst = dict(probabilities=0.0, preferences=0.0, values=0.0)
    counts = dict(uniform=0, floor=0, interest=0, goal=0, collision=0, truncated=0)
    for (state, action, drawn, evaluations, next_state, terminated, truncated), (p, v) in zip(
        recorder.steps, recorder.tables, strict=True
    ):
        pi = oracle.policy(state)
        worst["probabilities"] = max(worst["probabilities"], np.abs(pi - drawn).max())
        counts["uniform"] += oracle.interest == 0.0
        counts["floor"] += 0.0 < oracle.interest <= MIN_TEMPERATURE
        counts["interest"] += MIN_TEMPERATURE < oracle.interest < MAX_TEMPERATURE
        counts["goal"] += evaluations[0] > 0
        counts["collision"] += evaluations[1] == 1.0
        counts["truncated"] += truncated
        stream_evaluations = evaluations if two_streams else (evaluations[0] - evaluations[1],)
        oracle.step(state, action, stream_evaluations, next_state, terminated, truncated)
        worst["preferences"] = max(worst["preferences"], np.abs(oracle.preferences - p).max())
        worst["values"] = max(worst["values"], np.abs(oracle.values - v).max())
    return worst | counts


def test_oracle_is_eq_7_to_10_by_hand():
    oracle = TabularActorCritic(
        np.array([[0.0, 0.0, 0.0, 0.0], [1.27, 0.0, 0.0, 0.0]]),
        np.array([[1.0, 2.0], [0.5, 0.2]]),  # V_R, V_P of states 0 and 1
        gammas=(0.9, 0.1),
        alphas=(0.5, 0.25),
        signs=(1.0, -1.0),
        beta=0.1,
        actor_update="preference",
        temperature="interest",
        min_temperature=0.5,
        max_temperature=10.0,
    )
    np.testing.assert_allclose(oracle.policy(1), 0.25)  # an episode's start: delta+ = 0, random actions
    oracle.step(0, 2, (0.0, 0.01), 1, terminated=False, truncated=False)
    # delta_R = 0 + 0.9 * 2 - 1 = 0.8, delta_P = 0.01 + 0.1 * 0.2 - 0.5 = -0.47 (eq. 7-8)
    np.testing.assert_allclose(oracle.values[:, 0], [1.0 + 0.5 * 0.8, 0.5 - 0.25 * 0.47])
    np.testing.assert_allclose(oracle.preferences[0], [0.0, 0.0, 0.1 * (0.8 + 0.47), 0.0])  # eq. 1, 10
    e = np.exp(1.0)  # T = delta+ = 0.8 + 0.47 = 1.27 (eq. 2, 9)
    np.testing.assert_allclose(oracle.policy(1), [e / (e + 3), 1 / (e + 3), 1 / (e + 3), 1 / (e + 3)])
    oracle.step(1, 0, (5.0, 0.01), 0, terminated=True, truncated=False)  # no successor value
    np.testing.assert_allclose(oracle.values[:, 1], [2.0 + 0.5 * 3.0, 0.2 - 0.25 * 0.19])
    np.testing.assert_allclose(oracle.preferences[1, 0], 1.27 + 0.1 * 3.19)
    np.testing.assert_allclose(oracle.policy(0), 0.25)  # the next episode starts at random


@pytest.mark.parametrize(("env_id", "seed"), RUNS)
def test_two_dim_a2c_is_the_papers_tabular_actor_critic(env_id, seed):
    model = tabular_two_dim_a2c(cell_env(env_id), seed)
    assert isinstance(model.policy.optimizer, th.optim.SGD) and model.policy.interest_net is None
    preferences, values = read_tables(model)
    oracle = TabularActorCritic(
        preferences,
        values,
        gammas=(GAMMA, PUNISHMENT_GAMMA),
        alphas=(2 * VF_COEF * LEARNING_RATE, 2 * PUNISHMENT_VF_COEF * LEARNING_RATE),
        signs=(1.0, -1.0),
        beta=LEARNING_RATE,
        actor_update="preference",
        temperature="interest",
        min_temperature=MIN_TEMPERATURE,
        max_temperature=MAX_TEMPERATURE,
    )
    recorder = StepRecorder(drawn_two_dim)
    model.learn(N_STEPS, callback=recorder)
    result = replay(oracle, recorder, two_streams=True)
    assert max(result["probabilities"], result["preferences"], result["values"]) < TOLERANCE, result
    assert min(result["uniform"], result["floor"], result["goal"], result["collision"], result["truncated"]) > 0, result
    assert result["interest"] > N_STEPS / 2, result  # the interest, not a clamp, set T on most steps


@pytest.mark.parametrize(("env_id", "seed"), RUNS)
def test_a2c_is_the_tabular_one_step_actor_critic(env_id, seed):
    model = tabular_a2c(cell_env(env_id), seed)
    preferences, values = read_tables(model)
    oracle = TabularActorCritic(
        preferences,
        values,
        gammas=(GAMMA,),
        alphas=(2 * VF_COEF * LEARNING_RATE,),
        signs=(1.0,),
        beta=LEARNING_RATE,
        actor_update="log_prob",
        temperature=1.0,
    )
    recorder = StepRecorder(drawn_a2c)
    model.learn(N_STEPS, callback=recorder)
    result = replay(oracle, recorder, two_streams=False)
    assert max(result["probabilities"], result["preferences"], result["values"]) < TOLERANCE, result
    assert min(result["goal"], result["collision"], result["truncated"]) > 0, result
