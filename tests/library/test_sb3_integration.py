"""TwoDimA2C behaves like any SB3 algorithm: VecEnvs, callbacks, save/load, evaluation, seeds, spaces."""

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import SubprocVecEnv

from sb3_twodrl import TwoDimA2C, TwoDimMultiInputPolicy
from tests.helpers.toy_envs import LatticeCorridor


class CountSteps(BaseCallback):
    def __init__(self) -> None:
        super().__init__()
        self.calls = 0

    def _on_step(self) -> bool:
        self.calls += 1
        return True


@pytest.mark.filterwarnings("ignore:rich is experimental")  # tqdm on SB3's progress bar
def test_dummy_vec_env_callback_and_progress_bar() -> None:
    callback = CountSteps()
    model = TwoDimA2C("MlpPolicy", make_vec_env("CartPole-v1", n_envs=3, seed=0), n_steps=4, seed=0)
    model.learn(120, callback=callback, progress_bar=True)
    assert model.num_timesteps == 120
    assert callback.calls == 40


def test_subproc_vec_env() -> None:
    env = make_vec_env("CartPole-v1", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv)
    try:
        model = TwoDimA2C("MlpPolicy", env, n_steps=4, seed=0).learn(64)
        assert model.num_timesteps == 64
    finally:
        env.close()


def test_save_load_round_trip(tmp_path: Path) -> None:
    model = TwoDimA2C("MlpPolicy", "CartPole-v1", seed=0, punishment_gamma=0.3, min_temperature=0.2).learn(300)
    assert model.policy.running_interest.item() > 0
    model.save(tmp_path / "model.zip")
    loaded = TwoDimA2C.load(tmp_path / "model.zip")

    assert loaded.punishment_gamma == 0.3
    assert loaded.policy.min_temperature == 0.2
    assert loaded.policy.running_interest.item() == model.policy.running_interest.item()
    obs = np.random.default_rng(0).normal(size=(50, 4)).astype(np.float32)
    np.testing.assert_array_equal(model.predict(obs, deterministic=True)[0], loaded.predict(obs, deterministic=True)[0])
    for name, tensor in model.policy.state_dict().items():
        assert th.equal(loaded.policy.state_dict()[name], tensor), name


def test_set_env_and_continue_learning(tmp_path: Path) -> None:
    model = TwoDimA2C("MlpPolicy", "CartPole-v1", seed=0).learn(100)
    model.save(tmp_path / "model.zip")
    loaded = TwoDimA2C.load(tmp_path / "model.zip", env=make_vec_env("CartPole-v1", n_envs=2, seed=1))
    loaded.learn(100, reset_num_timesteps=False)
    assert loaded.num_timesteps == 200
    loaded.set_env(make_vec_env("CartPole-v1", n_envs=2, seed=2))
    loaded.learn(100)
    assert loaded.num_timesteps == 100


def test_evaluate_policy_and_stochastic_predict() -> None:
    model = TwoDimA2C("MlpPolicy", "CartPole-v1", seed=0).learn(200)
    mean_reward, _ = evaluate_policy(model, model.get_env(), n_eval_episodes=3, deterministic=False)
    assert mean_reward > 0


def test_seeded_runs_are_reproducible() -> None:
    def train() -> dict[str, th.Tensor]:
        env = make_vec_env(LatticeCorridor, n_envs=2, seed=5)
        return TwoDimA2C("MlpPolicy", env, seed=5, gamma=0.9).learn(300).policy.state_dict()

    first, second = train(), train()
    for name, tensor in first.items():
        assert th.equal(second[name], tensor), name


@pytest.mark.parametrize("env_id", ["Pendulum-v1", "CartPole-v1"])
def test_box_and_discrete_action_spaces(env_id: str) -> None:
    model = TwoDimA2C("MlpPolicy", env_id, seed=0).learn(50)
    action, _ = model.predict(model.get_env().observation_space.sample(), deterministic=False)
    assert model.action_space.contains(action)


class MultiSpaceEnv(gym.Env):
    """Dict observations and MultiDiscrete actions; reward +1 for action (1, 2)."""

    observation_space = gym.spaces.Dict(
        {"position": gym.spaces.Box(-1, 1, (2,)), "flag": gym.spaces.Discrete(3)}  # type: ignore[dict-item]
    )
    action_space = gym.spaces.MultiDiscrete([2, 3])

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        reward = 1.0 if tuple(action) == (1, 2) else -0.1
        return self.observation_space.sample(), reward, False, False, {}


def test_dict_observations_and_multidiscrete_actions() -> None:
    model = TwoDimA2C("MultiInputPolicy", MultiSpaceEnv(), n_steps=8, seed=0).learn(64)
    assert isinstance(model.policy, TwoDimMultiInputPolicy)
    assert model.rollout_buffer.punishments.max() == pytest.approx(0.1)
    values = model.policy.predict_punishment_values(model.policy.obs_to_tensor(MultiSpaceEnv().reset()[0])[0])
    assert values.shape == (1, 1)


class ImageBitsEnv(gym.Env):
    """Image observations and MultiBinary actions; reward +1 per set bit."""

    observation_space = gym.spaces.Box(0, 255, (36, 36, 1), dtype=np.uint8)
    action_space = gym.spaces.MultiBinary(3)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        return self.observation_space.sample(), float(np.sum(action)), False, False, {}


def test_image_observations_and_multibinary_actions() -> None:
    model = TwoDimA2C("CnnPolicy", ImageBitsEnv(), n_steps=4, seed=0).learn(16)
    action, _ = model.predict(ImageBitsEnv().observation_space.sample(), deterministic=False)
    assert model.action_space.contains(action.astype(np.int8))


@pytest.mark.skipif(not th.cuda.is_available(), reason="no CUDA device")
def test_cuda_device() -> None:
    model = TwoDimA2C("MlpPolicy", "CartPole-v1", device="cuda", seed=0).learn(50)
    assert model.policy.running_interest.device.type == "cuda"


def test_temperature_settings_are_algorithm_arguments(tmp_path: Path) -> None:
    """Not policy kwargs: ``load(..., policy_kwargs=...)`` with the kwargs trained with works, as in SB3."""
    policy_kwargs = dict(net_arch=[32])
    model = TwoDimA2C(
        "MlpPolicy", "CartPole-v1", use_rms_prop=False, policy_kwargs=policy_kwargs, max_temperature=3.0, seed=0
    )
    assert model.policy_kwargs == policy_kwargs
    model.save(tmp_path / "model.zip")
    loaded = TwoDimA2C.load(tmp_path / "model.zip", policy_kwargs=dict(net_arch=[32]))
    assert loaded.max_temperature == loaded.policy.max_temperature == 3.0


def test_load_with_custom_objects(tmp_path: Path) -> None:
    TwoDimA2C("MlpPolicy", "CartPole-v1", seed=0).save(tmp_path / "model.zip")
    loaded = TwoDimA2C.load(tmp_path / "model.zip", custom_objects=dict(punishment_gamma=0.4, learning_rate=1e-3))
    assert loaded.punishment_gamma == loaded.rollout_buffer.punishment_gamma == 0.4
    assert loaded.learning_rate == 1e-3


def test_loading_a_stock_a2c_file_says_so(tmp_path: Path) -> None:
    A2C("MlpPolicy", "CartPole-v1", seed=0).save(tmp_path / "a2c.zip")
    with pytest.raises(ValueError, match="saved by another algorithm"):
        TwoDimA2C.load(tmp_path / "a2c.zip")
