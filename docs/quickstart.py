import gymnasium as gym
import torch
from stable_baselines3.common.env_util import make_vec_env

import envs  # noqa: F401  (registers NomadOffice-v0 and the other Nomad office IDs)
from sb3_twodrl import TwoDimA2C, hyperparams

torch.set_num_threads(1)  # small networks: one thread is fastest, several contend for the cores
# The packaged settings: 64 robots, learning rate 3e-3, ent_coef 0.05, 1M steps (about a minute on 2 cores).
hp = hyperparams.load("twoda2c", "NomadOffice-v0")
env = make_vec_env("NomadOffice-v0", n_envs=hp.n_envs, seed=0)
model = TwoDimA2C(hp.policy, env, seed=0, **hp.kwargs)
model.learn(hp.n_timesteps, callback=hp.callbacks(), progress_bar=True)
model.save("twoda2c_nomad")

# 20 test episodes, deterministic actions: expect "goal rate: 1.00".
model = TwoDimA2C.load("twoda2c_nomad")
test_env = gym.make("NomadOffice-v0")
goals = 0
for episode in range(20):
    obs, _ = test_env.reset(seed=episode)
    done = False
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, info = test_env.step(action)
        done = terminated or truncated
    goals += info["is_success"]
print(f"goal rate: {goals / 20:.2f}")
