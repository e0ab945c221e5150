"""The 2D statistics logged at an update are those of the rollout it learned from."""

import numpy as np
import pytest
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.utils import explained_variance
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_twodrl import TwoDimA2C
from tests.helpers.toy_envs import ScriptedFeedbackEnv

# A different cycle of (net reward, r_P) per env, so that a mix-up between envs shows
CYCLES = [
    [(1.0, {"punishment": 0.0}), (-1.0, {"punishment": 1.0})],
    [(0.0, {"punishment": 2.0}), (0.5, {"punishment": 0.0}), (0.0, {"punishment": 0.0})],
    [(0.2, {"punishment": 0.5})],
]
ARRAYS = ("punishment_values", "punishment_returns", "interests", "utilities", "punishments", "inverse_temperatures")


class RolloutCopy(BaseCallback):
    """Copies the rollout buffer's 2D arrays at the end of the rollout, before the update reads them."""

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        self.arrays = {name: getattr(self.model.rollout_buffer, name).copy() for name in ARRAYS}


def test_logged_statistics_match_the_rollout() -> None:
    env = DummyVecEnv([lambda cycle=cycle: ScriptedFeedbackEnv(cycle) for cycle in CYCLES])
    copy = RolloutCopy()
    model = TwoDimA2C("MlpPolicy", env, n_steps=4, seed=0).learn(4 * len(CYCLES), callback=copy)
    logged, rollout = model.logger.name_to_value, copy.arrays
    inverse = rollout["inverse_temperatures"]
    expected = {
        "train/punishment_explained_variance": explained_variance(
            rollout["punishment_values"].ravel(), rollout["punishment_returns"].ravel()
        ),
        "train/interest": rollout["interests"].mean(),
        "train/utility": rollout["utilities"].mean(),
        "train/temperature": np.mean(1.0 / inverse[inverse > 0]),
        "rollout/punishment_mean": rollout["punishments"].mean(),
    }
    for key, value in expected.items():
        assert logged[key] == pytest.approx(value, rel=1e-5, abs=1e-6), key  # float32 sums in another order
    assert "train/punishment_value_loss" in logged
