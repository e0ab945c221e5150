"""Each critic learns the discounted sum of its own stream with its own gamma (eq. 3-8)."""

import numpy as np
import torch as th
from gymnasium.wrappers import TimeLimit
from stable_baselines3.common.env_util import make_vec_env

from sb3_twodrl import TwoDimA2C
from tests.helpers.toy_envs import TwoStateChain

GAMMA_R, GAMMA_P = 0.9, 0.5


def test_two_critics_converge_to_their_discounted_sums() -> None:
    # Truncation every 30 steps checks the time-limit bootstrap too: without it V_R would sag.
    env = make_vec_env(lambda: TimeLimit(TwoStateChain(), 30), n_envs=4, seed=0)
    model = TwoDimA2C(
        "MlpPolicy",
        env,
        gamma=GAMMA_R,
        punishment_gamma=GAMMA_P,
        gae_lambda=0.0,
        n_steps=8,
        learning_rate=0.03,
        use_rms_prop=False,
        policy_kwargs=dict(net_arch=[], ortho_init=False),
        seed=0,
    ).learn(12_000)

    states = th.eye(2)
    with th.no_grad():
        reward_values = model.policy.predict_values(states).flatten().numpy()
        punishment_values = model.policy.predict_punishment_values(states).flatten().numpy()
    # Eq. 3: r_R = 1 in state 0 only; eq. 4: r_P = 1 in state 1 only; the states alternate.
    expected_r = np.array([1.0, GAMMA_R]) / (1 - GAMMA_R**2)
    expected_p = np.array([GAMMA_P, 1.0]) / (1 - GAMMA_P**2)
    np.testing.assert_allclose(reward_values, expected_r, rtol=0.05)
    np.testing.assert_allclose(punishment_values, expected_p, rtol=0.05)
