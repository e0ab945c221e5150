from sb3_twodrl.a2c.policies import CnnPolicy, MlpPolicy, MultiInputPolicy
from sb3_twodrl.a2c.twodim_a2c import TwoDimA2C

__all__ = ["CnnPolicy", "MlpPolicy", "MultiInputPolicy", "TwoDimA2C"]
