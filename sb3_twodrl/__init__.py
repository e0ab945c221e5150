"""Two-dimensional evaluation reinforcement learning (2D-RL) for Stable-Baselines3."""

from stable_baselines3 import A2C, PPO
from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_twodrl import callbacks
from sb3_twodrl.a2c import TwoDimA2C
from sb3_twodrl.callbacks import NavigationMetricsCallback
from sb3_twodrl.common.policies import TwoDimActorCriticCnnPolicy, TwoDimActorCriticPolicy, TwoDimMultiInputPolicy
from sb3_twodrl.ppo import TwoDimPPO

__version__ = "0.1.0"
"""The package's version: ``pyproject.toml`` reads it from here; ``CHANGELOG.md`` says what each one changed."""

ALGOS: dict[str, type[BaseAlgorithm]] = {"a2c": A2C, "ppo": PPO, "twoda2c": TwoDimA2C, "twodppo": TwoDimPPO}
"""The algorithms by their rl-zoo3 names, the 2D-RL ones beside their stock baselines."""

__all__ = [
    "ALGOS",
    "NavigationMetricsCallback",
    "TwoDimA2C",
    "TwoDimActorCriticCnnPolicy",
    "TwoDimActorCriticPolicy",
    "TwoDimMultiInputPolicy",
    "TwoDimPPO",
    "__version__",
    "callbacks",
]
