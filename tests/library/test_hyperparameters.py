"""Bad hyperparameters fail at construction with a ValueError naming the argument."""

from typing import Any

import gymnasium as gym
import pytest

from sb3_twodrl import TwoDimA2C


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(gamma=1.5), "gamma"),
        (dict(punishment_gamma=-0.1), "punishment_gamma"),
        (dict(gae_lambda=2.0), "gae_lambda"),
        (dict(punishment_gae_lambda=1.1), "punishment_gae_lambda"),
        (dict(vf_coef=-1.0), "vf_coef"),
        (dict(ent_coef=-0.1), "ent_coef"),
        (dict(punishment_vf_coef=-0.5), "punishment_vf_coef"),
        (dict(punishment_weight=-1.0), "punishment_weight"),
        (dict(punishment_weight=float("nan")), "punishment_weight"),
        (dict(min_temperature=2.0, max_temperature=1.0), "min_temperature"),
        (dict(min_temperature=0.0), "min_temperature"),
        (dict(max_temperature=float("inf")), "max_temperature"),
        (dict(temperature="hot"), "temperature"),
        (dict(temperature=-1.0), "temperature"),
        (dict(reward_split=3), "reward_split"),
        (dict(n_steps=0), "n_steps"),
        (dict(max_temperature="10"), "max_temperature"),
    ],
)
def test_bad_hyperparameter(kwargs: dict[str, Any], name: str) -> None:
    with pytest.raises(ValueError, match=name):
        TwoDimA2C("MlpPolicy", "CartPole-v1", **kwargs)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(punishment_gamma="a"), "punishment_gamma"),
        (dict(gamma=None), "gamma"),
        (dict(punishment_weight=True), "punishment_weight"),
        (dict(punishment_vf_coef="0.5"), "punishment_vf_coef"),
        (dict(n_steps=5.0), "n_steps"),
    ],
)
def test_a_hyperparameter_of_the_wrong_type_is_a_type_error(kwargs: dict[str, Any], name: str) -> None:
    with pytest.raises(TypeError, match=name):
        TwoDimA2C("MlpPolicy", "CartPole-v1", **kwargs)


def test_unsupported_action_space() -> None:
    class TupleActions(gym.Env):
        observation_space = gym.spaces.Box(0, 1, (1,))
        action_space = gym.spaces.Tuple([gym.spaces.Discrete(2), gym.spaces.Discrete(2)])

    with pytest.raises(AssertionError, match="only supports"):
        TwoDimA2C("MlpPolicy", TupleActions())
