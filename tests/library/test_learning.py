"""Long learning checks (``pytest -m slow``)."""

import pytest
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_twodrl import TwoDimA2C, TwoDimPPO

# rl-zoo3's PPO entry for CartPole-v1 (sb3_twodrl/hyperparams/twodppo.yml), the 2D-RL arguments at their defaults
PPO_CARTPOLE = dict(
    n_steps=32,
    batch_size=256,
    gae_lambda=0.8,
    gamma=0.98,
    n_epochs=20,
    ent_coef=0.0,
    learning_rate=lambda progress: progress * 0.001,
    clip_range=lambda progress: progress * 0.2,
)


def cartpole_return(algo: type, seed: int, **kwargs) -> float:
    """Mean return over 20 deterministic episodes after 100k steps with 8 envs (a random policy: about 22)."""
    model = algo("MlpPolicy", make_vec_env("CartPole-v1", n_envs=8, seed=seed), seed=seed, **kwargs).learn(100_000)
    eval_env = make_vec_env("CartPole-v1", n_envs=1, seed=seed + 100)
    mean_return, _ = evaluate_policy(model, eval_env, n_eval_episodes=20, deterministic=True)
    return float(mean_return)


@pytest.mark.slow
def test_learns_cartpole_within_100k_steps_at_sb3s_defaults_for_two_of_three_seeds() -> None:
    """SB3's A2C defaults are not tuned for CartPole, so "learned" is half the episode limit (250), not solved:
    under MKL_CBWR=COMPATIBLE seeds 0-5 gave 304, 500, 383, 500, 498, 468 (stock A2C: 500, 500, 500, 141, 190,
    129)."""
    returns = [cartpole_return(TwoDimA2C, seed) for seed in range(3)]
    assert sum(r >= 250 for r in returns) >= 2, returns


@pytest.mark.slow
def test_twodppo_solves_cartpole_within_100k_steps_for_two_of_three_seeds() -> None:
    """At rl-zoo3's tuned entry: solved is a mean return of at least 400."""
    solved: list[bool] = []
    for seed in range(3):
        if sum(solved) >= 2 or len(solved) - sum(solved) >= 2:  # decided: the third seed cannot change the verdict
            break
        solved.append(cartpole_return(TwoDimPPO, seed, device="cpu", **PPO_CARTPOLE) >= 400)
    assert sum(solved) >= 2, solved
