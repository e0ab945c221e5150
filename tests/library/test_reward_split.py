"""Each ``reward_split`` mode turns (reward, info) into the right (r_R, r_P), and bad feedback is caught."""

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sb3_twodrl import TwoDimA2C
from sb3_twodrl.common.splitting import PYTHON_CHECK_MAX_ENVS, SPLIT_MODES, make_reward_split, split_rewards
from tests.helpers.toy_envs import ScriptedFeedbackEnv

FEEDBACK: dict[str, list[tuple[float, dict[str, Any]]]] = {
    "info": [(4.99, {"punishment": 0.01}), (-1.0, {"punishment": 1.0})],
    "cost": [(2.0, {"cost": 0.5}), (-3.0, {"cost": 0.0})],
    "sign": [(2.0, {}), (-3.0, {})],
    "none": [(2.0, {"punishment": 1.0}), (-3.0, {})],
}
EXPECTED = {
    "info": ([5.0, 0.0], [0.01, 1.0]),
    "cost": ([2.0, -3.0], [0.5, 0.0]),
    "sign": ([2.0, 0.0], [0.0, 3.0]),
    "none": ([2.0, -3.0], [0.0, 0.0]),
}


def rollout_streams(feedback: list, reward_split: Any) -> tuple[np.ndarray, np.ndarray]:
    model = TwoDimA2C("MlpPolicy", ScriptedFeedbackEnv(feedback), n_steps=4, reward_split=reward_split, seed=0)
    model.learn(4)
    return model.rollout_buffer.rewards[:, 0], model.rollout_buffer.punishments[:, 0]


@pytest.mark.parametrize("mode", ["info", "cost", "sign", "none"])
def test_named_modes(mode: str) -> None:
    rewards, punishments = rollout_streams(FEEDBACK[mode], mode)
    reward_r, reward_p = EXPECTED[mode]
    np.testing.assert_allclose(rewards, reward_r * 2, atol=1e-6)
    np.testing.assert_allclose(punishments, reward_p * 2, atol=1e-6)


@pytest.mark.parametrize("mode", ["info", "cost", "sign"])
def test_auto_picks_the_mode_from_the_info_keys(mode: str) -> None:
    np.testing.assert_array_equal(rollout_streams(FEEDBACK[mode], "auto"), rollout_streams(FEEDBACK[mode], mode))


def test_auto_decides_per_env() -> None:
    infos = [{"punishment": 0.01}, {"cost": 0.5}, {}, {}]
    reward_r, reward_p = split_rewards(make_reward_split("auto"), np.array([4.99, -1.0, 2.0, -3.0]), infos, 1)
    np.testing.assert_allclose(reward_r, [5.0, -1.0, 2.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(reward_p, [0.01, 0.5, 0.0, 3.0], atol=1e-6)


def test_callable_split() -> None:
    rewards, punishments = rollout_streams([(1.5, {"danger": 0.25})], lambda r, info: (2 * r, info["danger"]))
    np.testing.assert_allclose(rewards, 3.0)
    np.testing.assert_allclose(punishments, 0.25)


@pytest.mark.parametrize("punishment", [-0.5, float("nan"), float("inf")])
def test_bad_punishment_is_an_error_at_its_step(punishment: float) -> None:
    feedback = [(0.0, {"punishment": 0.0})] * 6 + [(0.0, {"punishment": punishment})]
    model = TwoDimA2C("MlpPolicy", ScriptedFeedbackEnv(feedback), n_steps=4, seed=0)
    with pytest.raises(ValueError, match="at timestep 7"):
        model.learn(8)


@pytest.mark.filterwarnings("ignore:overflow encountered in cast")
@pytest.mark.parametrize("n_envs", [4, PYTHON_CHECK_MAX_ENVS + 1])  # both ways of checking
@pytest.mark.parametrize(
    ("reward", "cost"),
    [(float("nan"), 0.0), (float("-inf"), 0.0), (0.0, -0.5), (0.0, float("nan")), (0.0, float("inf")), (0.0, 1e300)],
)
def test_bad_feedback_names_the_env(n_envs: int, reward: float, cost: float) -> None:
    rewards, infos = np.zeros(n_envs), [{"cost": 0.0} for _ in range(n_envs)]
    rewards[2], infos[2] = reward, {"cost": cost}  # 1e300 is finite, but not in the float32 buffer
    with pytest.raises(ValueError, match="env 2 at timestep 3"):
        split_rewards(make_reward_split("cost"), rewards, infos, 3)


@pytest.mark.parametrize("n_envs", [8, PYTHON_CHECK_MAX_ENVS + 1])
def test_large_finite_feedback_passes(n_envs: int) -> None:
    rewards = np.full(n_envs, 3e38, dtype=np.float32)  # their sum overflows float32, no value does
    reward_r, reward_p = split_rewards(make_reward_split("sign"), rewards, [{}] * n_envs, 1)
    np.testing.assert_array_equal(reward_r, rewards)
    np.testing.assert_array_equal(reward_p, 0.0)


def test_split_survives_save_and_load(tmp_path: Path) -> None:
    env = ScriptedFeedbackEnv(FEEDBACK["info"])
    TwoDimA2C("MlpPolicy", env, n_steps=4, reward_split="sign", seed=0).learn(4).save(tmp_path / "model.zip")
    loaded = TwoDimA2C.load(tmp_path / "model.zip", env=env).learn(4)
    np.testing.assert_allclose(loaded.rollout_buffer.punishments[:, 0], [0.0, 1.0, 0.0, 1.0], atol=1e-6)


def test_unknown_mode_is_rejected() -> None:
    with pytest.raises(ValueError, match="reward_split"):
        TwoDimA2C("MlpPolicy", "CartPole-v1", reward_split="net")


@pytest.mark.parametrize(("mode", "key"), [("info", "punishment"), ("cost", "cost")])
def test_a_missing_info_key_names_the_mode_and_the_key(mode: str, key: str) -> None:
    model = TwoDimA2C("MlpPolicy", ScriptedFeedbackEnv([(1.0, {"other": 0.0})]), n_steps=4, reward_split=mode)
    with pytest.raises(ValueError, match=rf'reward_split="{mode}" needs info\["{key}"\].*env 0.*timestep 1'):
        model.learn(4)


@pytest.mark.parametrize("value", ["high", [0.5, 0.5], {"p": 1.0}])
def test_an_info_value_that_is_no_number_is_an_error(value: Any) -> None:
    with pytest.raises(ValueError, match=r'info\["punishment"\] must be a real number'):
        split_rewards(make_reward_split("info"), np.zeros(2), [{"punishment": 0.0}, {"punishment": value}], 1)


@pytest.mark.parametrize("result", [1.0, (1.0, 2.0, 3.0), ("a", 0.0)])
def test_a_callable_that_returns_no_pair_is_an_error(result: Any) -> None:
    with pytest.raises(ValueError, match="must return a pair"):
        split_rewards(make_reward_split(lambda r, info: result), np.zeros(2), [{}, {}], 1)


@pytest.mark.parametrize("page", ["README.md", "docs/twodim_a2c.md"])
def test_the_argument_table_lists_every_mode(page: str) -> None:
    text = (Path(__file__).resolve().parents[2] / page).read_text()
    row = next(line for line in text.splitlines() if line.startswith("| `reward_split` |"))
    assert [mode for mode in SPLIT_MODES if f'`"{mode}"`' not in row] == []
