"""Policy aliases of TwoDimPPO (as SB3's ``ppo/policies.py``)."""

from sb3_twodrl.common.policies import TwoDimActorCriticCnnPolicy, TwoDimActorCriticPolicy, TwoDimMultiInputPolicy

MlpPolicy = TwoDimActorCriticPolicy
CnnPolicy = TwoDimActorCriticCnnPolicy
MultiInputPolicy = TwoDimMultiInputPolicy
