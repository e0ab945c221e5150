"""Two-dimensional evaluation reinforcement learning (2D-RL) for Stable-Baselines3."""

from sb3_twodrl import callbacks
from sb3_twodrl.callbacks import NavigationMetricsCallback
from sb3_twodrl.policies import TwoDimActorCriticCnnPolicy, TwoDimActorCriticPolicy, TwoDimMultiInputPolicy
from sb3_twodrl.twodim_a2c import TwoDimA2C

__all__ = [
    "NavigationMetricsCallback",
    "TwoDimA2C",
    "TwoDimActorCriticCnnPolicy",
    "TwoDimActorCriticPolicy",
    "TwoDimMultiInputPolicy",
    "callbacks",
]
