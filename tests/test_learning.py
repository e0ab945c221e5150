"""Long learning checks (``pytest -m slow``)."""

import pytest
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_twodrl import TwoDimA2C


@pytest.mark.slow
def test_solves_cartpole_within_100k_steps_for_two_of_three_seeds() -> None:
    solved = []
    for seed in range(3):
        model = TwoDimA2C("MlpPolicy", make_vec_env("CartPole-v1", n_envs=8, seed=seed), seed=seed).learn(100_000)
        eval_env = make_vec_env("CartPole-v1", n_envs=1, seed=seed + 100)
        mean_return, _ = evaluate_policy(model, eval_env, n_eval_episodes=20, deterministic=True)
        solved.append(mean_return >= 400)
    assert sum(solved) >= 2, solved
