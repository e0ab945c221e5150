"""Policy aliases of TwoDimA2C (as SB3's ``a2c/policies.py``)."""

from sb3_twodrl.common.policies import TwoDimActorCriticCnnPolicy, TwoDimActorCriticPolicy, TwoDimMultiInputPolicy

MlpPolicy = TwoDimActorCriticPolicy
CnnPolicy = TwoDimActorCriticCnnPolicy
MultiInputPolicy = TwoDimMultiInputPolicy
