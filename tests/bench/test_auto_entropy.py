"""The self-tuning entropy arms (twodrl_bench.algorithms.auto_entropy): SAC's learned coefficient on the on-policy
algorithms."""

import inspect
import math
from pathlib import Path

import numpy as np
import pytest
import torch as th
import yaml
from gymnasium import spaces
from stable_baselines3 import A2C, PPO
from stable_baselines3.common.envs import IdentityEnv, IdentityEnvMultiDiscrete

import twodrl_bench
from sb3_twodrl import TwoDimA2C, TwoDimPPO
from twodrl_bench.algorithms import ALGOS
from twodrl_bench.algorithms.auto_entropy import (
    TARGET_FRACTION,
    AutoEntropyA2C,
    AutoEntropyPPO,
    AutoEntropyTwoDimA2C,
    AutoEntropyTwoDimPPO,
    max_entropy,
)
from twodrl_bench.checkpoint import load_checkpoint, save_checkpoint, set_rng_state
from twodrl_bench.settings import constructor_defaults

PPO_ARGS = dict(n_steps=32, batch_size=16, n_epochs=2)
AUTO = [(AutoEntropyA2C, {}), (AutoEntropyPPO, PPO_ARGS), (AutoEntropyTwoDimA2C, {}), (AutoEntropyTwoDimPPO, PPO_ARGS)]


def _peaked(model, lead: float) -> None:
    """Make the actor prefer action 0 by ``lead`` in every state (its weights 0, its bias ``[lead, 0, ...]``)."""
    with th.no_grad():
        model.policy.action_net.weight.zero_()
        model.policy.action_net.bias.zero_()
        model.policy.action_net.bias[0] = lead


@pytest.mark.parametrize("algo, kwargs", AUTO)
def test_coefficient_falls_while_the_entropy_is_above_target(algo, kwargs) -> None:
    """A fresh actor is nearly uniform: its entropy is above half the maximum, so alpha falls."""
    model = algo(
        "MlpPolicy", IdentityEnv(4), target_entropy_fraction=0.5, ent_coef_lr=0.01, seed=1, device="cpu", **kwargs
    )
    model.learn(200 if not kwargs else 64)
    assert model.target_entropy == pytest.approx(0.5 * math.log(4))
    assert model.logger.name_to_value["train/entropy"] > model.target_entropy
    assert model.ent_coef < 1.0
    assert model.logger.name_to_value["train/ent_coef"] < 1.0


@pytest.mark.parametrize("algo, kwargs", AUTO)
def test_coefficient_rises_while_the_entropy_is_below_target(algo, kwargs) -> None:
    """An actor that all but always takes one action has entropy below 0.98 of the maximum: alpha rises."""
    model = algo("MlpPolicy", IdentityEnv(4), ent_coef_lr=0.01, seed=1, device="cpu", **kwargs)
    _peaked(model, 8.0)
    model.learn(200 if not kwargs else 64)
    assert model.logger.name_to_value["train/entropy"] < model.target_entropy
    assert model.ent_coef > 1.0


def test_the_2d_coefficient_follows_the_tempered_policy_that_acts() -> None:
    """Preferences that lead by 3 (entropy 0.38 of the maximum) acted on at T = 5 (0.97 of it): against a
    target of 0.9 the tempered entropy is above it, and alpha falls."""
    model = AutoEntropyTwoDimA2C(
        "MlpPolicy",
        IdentityEnv(4),
        temperature=5.0,
        target_entropy_fraction=0.9,
        ent_coef_lr=0.01,
        seed=1,
        device="cpu",
    )
    _peaked(model, 3.0)
    model.learn(100)
    assert model.logger.name_to_value["train/entropy"] > 0.9 * math.log(4)
    assert model.ent_coef < 1.0


def test_ppo_steps_the_coefficient_once_per_minibatch() -> None:
    model = AutoEntropyPPO("MlpPolicy", IdentityEnv(4), seed=1, device="cpu", **PPO_ARGS)
    model.learn(32)
    assert len(model._ent_coef_stats) == PPO_ARGS["n_epochs"] * PPO_ARGS["n_steps"] // PPO_ARGS["batch_size"]


def _assert_same_parameters(expected: th.nn.Module, actual: th.nn.Module) -> None:
    actual_state = actual.state_dict()
    for name, tensor in expected.state_dict().items():
        assert th.equal(actual_state[name], tensor), name


@pytest.mark.parametrize(
    "auto, stock, ent_coef, coefficient, kwargs",
    [
        (AutoEntropyA2C, A2C, "auto_0.05", 0.05, {}),
        (AutoEntropyA2C, A2C, 0.05, 0.05, {}),
        (AutoEntropyPPO, PPO, "auto", 1.0, PPO_ARGS),
        (AutoEntropyTwoDimA2C, TwoDimA2C, "auto_0.05", 0.05, {}),
        (AutoEntropyTwoDimPPO, TwoDimPPO, "auto", 1.0, PPO_ARGS),
    ],
)
def test_at_a_fixed_coefficient_a_seeded_run_is_the_stock_algorithms_bitwise(
    auto, stock, ent_coef, coefficient, kwargs
) -> None:
    """With ``ent_coef_lr=0`` (the update runs and moves nothing) or a float ``ent_coef``: stock SB3's (or the
    2D class's) parameters after ``learn``, bit for bit."""
    expected = stock("MlpPolicy", "CartPole-v1", ent_coef=coefficient, seed=3, device="cpu", **kwargs).learn(400)
    actual = auto("MlpPolicy", "CartPole-v1", ent_coef=ent_coef, ent_coef_lr=0.0, seed=3, device="cpu", **kwargs)
    actual.learn(400)
    _assert_same_parameters(expected.policy, actual.policy)
    assert actual.ent_coef == coefficient


@pytest.mark.parametrize("algo", [AutoEntropyA2C, AutoEntropyTwoDimA2C])
def test_save_and_load_keep_the_learned_coefficient(algo, tmp_path) -> None:
    model = algo("MlpPolicy", IdentityEnv(4), target_entropy_fraction=0.5, ent_coef_lr=0.01, seed=1, device="cpu")
    model.learn(100)
    model.save(tmp_path / "model.zip")
    loaded = algo.load(tmp_path / "model.zip", device="cpu")
    assert th.equal(loaded.log_ent_coef_ratio, model.log_ent_coef_ratio)
    assert loaded.log_ent_coef_ratio.item() < 0.0
    assert loaded.ent_coef_optimizer.param_groups[0]["params"][0] is loaded.log_ent_coef_ratio
    exp_avg = loaded.ent_coef_optimizer.state_dict()["state"][0]["exp_avg"]
    assert th.equal(exp_avg, model.ent_coef_optimizer.state_dict()["state"][0]["exp_avg"])
    assert (loaded.target_entropy, loaded.ent_coef_init) == (model.target_entropy, 1.0)


@pytest.mark.parametrize("algo, kwargs", [(AutoEntropyA2C, {}), (AutoEntropyTwoDimPPO, PPO_ARGS)])
def test_a_run_resumed_from_a_checkpoint_learns_what_an_uninterrupted_one_does(algo, kwargs, tmp_path) -> None:
    """The bench's checkpoints (twodrl_bench.checkpoint) carry the coefficient and its optimizer."""
    model = algo(
        "MlpPolicy", "CartPole-v1", target_entropy_fraction=0.5, ent_coef_lr=0.01, seed=5, device="cpu", **kwargs
    )
    model.learn(128)
    save_checkpoint(tmp_path / "run.pkl", model, {})
    model.learn(128, reset_num_timesteps=False)
    resumed, rng, _ = load_checkpoint(tmp_path / "run.pkl")
    set_rng_state(rng)
    resumed.learn(128, reset_num_timesteps=False)
    _assert_same_parameters(model.policy, resumed.policy)
    assert th.equal(resumed.log_ent_coef_ratio, model.log_ent_coef_ratio)
    assert resumed.ent_coef_optimizer.param_groups[0]["params"][0] is resumed.log_ent_coef_ratio


def test_the_target_is_a_fraction_of_the_maximum_entropy() -> None:
    assert max_entropy(spaces.Discrete(4)) == pytest.approx(math.log(4))
    assert max_entropy(spaces.MultiDiscrete([2, 3])) == pytest.approx(math.log(6))
    assert max_entropy(spaces.MultiBinary(3)) == pytest.approx(3 * math.log(2))
    model = AutoEntropyA2C("MlpPolicy", IdentityEnvMultiDiscrete(2), seed=0, device="cpu")
    assert model.target_entropy == pytest.approx(TARGET_FRACTION * 2 * math.log(2))


def test_the_recorded_defaults_hold_the_base_defaults_and_the_new_arguments() -> None:
    """The bench records a class's constructor defaults along the ``__init__`` chain (a subclass's default wins)."""
    defaults = constructor_defaults(AutoEntropyTwoDimA2C)
    assert defaults["ent_coef"] == "auto"
    assert defaults["target_entropy_fraction"] == TARGET_FRACTION
    assert defaults["ent_coef_lr"] is None
    assert defaults["punishment_gamma"] == inspect.signature(TwoDimA2C.__init__).parameters["punishment_gamma"].default
    auto = {name: cls for name, cls in ALGOS.items() if name.endswith("_auto")}
    assert auto == {
        "a2c_auto": AutoEntropyA2C,
        "ppo_auto": AutoEntropyPPO,
        "twoda2c_auto": AutoEntropyTwoDimA2C,
        "twodppo_auto": AutoEntropyTwoDimPPO,
    }


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"target_entropy_fraction": 0.0}, "target_entropy_fraction must be in \\(0, 1\\], got 0.0"),
        ({"target_entropy_fraction": 1.5}, "target_entropy_fraction must be in \\(0, 1\\], got 1.5"),
        ({"target_entropy_fraction": -0.1}, "target_entropy_fraction must be in \\(0, 1\\], got -0.1"),
        ({"target_entropy_fraction": math.nan}, "target_entropy_fraction must be in \\(0, 1\\], got nan"),
        ({"ent_coef": "autox"}, "ent_coef must be .*got 'autox'"),
        ({"ent_coef": "auto_0"}, "ent_coef must be .*got 'auto_0'"),
        ({"ent_coef": "auto_-1"}, "ent_coef must be .*got 'auto_-1'"),
        ({"ent_coef": "auto_x"}, "ent_coef must be .*got 'auto_x'"),
        ({"ent_coef": -0.1}, "ent_coef must be finite and >= 0, got -0.1"),
        ({"ent_coef_lr": -1.0}, "ent_coef_lr must be finite and >= 0, got -1.0"),
    ],
)
@pytest.mark.parametrize("algo", [AutoEntropyA2C, AutoEntropyTwoDimPPO])
def test_bad_arguments_are_refused(algo, kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        algo("MlpPolicy", IdentityEnv(4), device="cpu", **kwargs)


@pytest.mark.parametrize("algo", [AutoEntropyA2C, AutoEntropyTwoDimA2C])
def test_a_box_action_space_is_refused(algo) -> None:
    with pytest.raises(ValueError, match="action_space must be Discrete, MultiDiscrete or MultiBinary, got Box"):
        algo("MlpPolicy", "Pendulum-v1", device="cpu")
    algo("MlpPolicy", "Pendulum-v1", ent_coef=0.01, device="cpu")  # a fixed coefficient needs no target


def test_a_fixed_coefficient_learns_nothing_and_logs_nothing_more() -> None:
    model = AutoEntropyA2C("MlpPolicy", IdentityEnv(4), ent_coef=0.05, seed=0, device="cpu").learn(50)
    assert model.log_ent_coef_ratio is None and model.ent_coef == 0.05
    assert "train/ent_coef" not in model.logger.name_to_value
    assert np.isfinite(model.logger.name_to_value["train/entropy_loss"])


def test_the_studys_specs_name_their_paths_and_known_algorithms() -> None:
    """Each spec of the study is named by its path, runs seeds 400-409, and gives every automatic arm a
    valid target; its algorithms are the stock, 2D-RL or automatic ones."""
    root = Path(twodrl_bench.__file__).parent / "specs"
    paths = sorted((root / "auto_entropy").glob("*.yml"))
    assert [p.stem for p in paths] == [
        "CliffWalking",
        "LavaGap",
        "LunarLander",
        "LunarLander_ppo",
        "NomadOffice-v0",
        "NomadOffice-v0_ppo",
    ]
    for path in paths:
        spec = yaml.safe_load(path.read_text())
        assert spec["name"] == str(path.relative_to(root).with_suffix(""))
        assert spec["seeds"] == list(range(400, 410))
        for arm in spec["arms"].values():
            assert arm["algo"] in {
                "a2c",
                "ppo",
                "twoda2c",
                "twodppo",
                "a2c_auto",
                "ppo_auto",
                "twoda2c_auto",
                "twodppo_auto",
            }
            if arm["algo"].endswith("_auto"):
                assert arm["override"]["ent_coef"] == "auto"
                assert arm["override"]["target_entropy_fraction"] in (0.98, 0.5)
        rules = spec["rules"]
        assert {rules["claim"], *rules["against"], rules["zero"]} <= set(spec["arms"])


@pytest.mark.parametrize("algo, kwargs", [(AutoEntropyA2C, {}), (AutoEntropyTwoDimPPO, PPO_ARGS)])
def test_the_coefficients_course_is_kept_per_tenth_of_the_budget_and_saved(algo, kwargs, tmp_path) -> None:
    """Each tenth of learn's budget holds its last train's step count, alpha and entropy fraction; the last
    tenth holds the final coefficient; the course survives save and load."""
    budget = 320  # PPO_ARGS: one rollout of 32 steps per tenth
    model = algo(
        "MlpPolicy", IdentityEnv(4), target_entropy_fraction=0.5, ent_coef_lr=0.01, seed=1, device="cpu", **kwargs
    )
    model.learn(budget)
    course = model.ent_coef_course
    assert all(point is not None for point in course)
    steps = [point[0] for point in course]
    assert steps == sorted(steps) and steps[-1] == model.num_timesteps
    for tenth, (timesteps, _, _) in enumerate(course, start=1):
        assert (tenth - 1) * budget / 10 < timesteps <= tenth * budget / 10
    alphas = [point[1] for point in course]
    assert alphas == sorted(alphas, reverse=True)  # entropy above target all along: alpha falls
    assert all(0.5 < point[2] <= 1.0 for point in course)
    model.save(tmp_path / "model.zip")
    assert algo.load(tmp_path / "model.zip", device="cpu").ent_coef_course == course


def test_an_epoch_runs_rows_carry_the_coefficient_of_a_learned_one_only(tmp_path) -> None:
    """The paper's epochs (no set budget): each row holds the last update's alpha and entropy fraction."""
    import twodrl_envs  # noqa: F401  (registers the IDs)
    from twodrl_bench import Experiment, run_job

    hp = {"n_envs": 4, "gamma": 0.9, "n_steps": 5}
    auto = {**hp, "ent_coef": "auto", "target_entropy_fraction": 0.5, "ent_coef_lr": 0.01}
    spec = {
        "name": "auto",
        "env": "NomadOffice-v0",
        "protocol": {"epochs": 2, "learn_episodes": 4, "test_episodes": 2, "tensorboard": False},
        "seeds": [3],
        "arms": {"auto": {"algo": "a2c_auto", "override": auto}, "stock": {"algo": "a2c", "override": hp}},
        "report": "paper",
    }
    auto_job, stock_job = Experiment.from_spec(spec).jobs(tmp_path)
    rows = run_job(auto_job)
    assert [row["ent_coef"] < 1.0 for row in rows] == [True, True]  # a fresh actor is above half the maximum
    assert rows[1]["ent_coef"] < rows[0]["ent_coef"] and all(0.5 < row["entropy_fraction"] <= 1 for row in rows)
    stock = run_job(stock_job)
    assert "ent_coef" not in stock[0] and "entropy_fraction" not in stock[0]
