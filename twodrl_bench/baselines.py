"""The stock arms of the experiments: SB3's A2C and PPO with the same results, bit for bit, in less time.

:class:`~sb3_twodrl.common.fast.FastActorCriticPolicy` computes SB3's forward pass and action
scores with the same tensor operations and fewer Python calls; :class:`~sb3_twodrl.common.infos.BatchInfosMixin`
reads a batched env's info arrays without building every env's dict. Neither changes a number:
``tests/test_fast.py`` checks the parameters after learning against stock SB3's bitwise. The
2D-RL algorithms have both already, so the two arms of a comparison run the same pipeline.
"""

from typing import ClassVar

from stable_baselines3 import A2C, PPO
from stable_baselines3.common.policies import BasePolicy

from sb3_twodrl.common.fast import FastActorCriticPolicy
from sb3_twodrl.common.infos import BatchInfosMixin


class BatchedA2C(BatchInfosMixin, A2C):
    """SB3's ``A2C``; its ``MlpPolicy`` is :class:`~sb3_twodrl.common.fast.FastActorCriticPolicy`."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {**A2C.policy_aliases, "MlpPolicy": FastActorCriticPolicy}


class BatchedPPO(BatchInfosMixin, PPO):
    """SB3's ``PPO``; its ``MlpPolicy`` is :class:`~sb3_twodrl.common.fast.FastActorCriticPolicy`."""

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {**PPO.policy_aliases, "MlpPolicy": FastActorCriticPolicy}


BASELINE_ALGOS: dict[str, type] = {"a2c": BatchedA2C, "ppo": BatchedPPO}
"""The stock arms by the experiment runner's names."""
