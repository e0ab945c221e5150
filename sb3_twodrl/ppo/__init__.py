from sb3_twodrl.ppo.policies import CnnPolicy, MlpPolicy, MultiInputPolicy
from sb3_twodrl.ppo.twodim_ppo import TwoDimPPO

__all__ = ["CnnPolicy", "MlpPolicy", "MultiInputPolicy", "TwoDimPPO"]
