"""The protocol's hyperparameters ship in the package and are found there; an env without an entry is an error."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import pytest

import sb3_twodrl
import twodrl_envs  # noqa: F401  (registers the Nomad office ids)
import twodrl_zoo
from twodrl_bench import Experiment, load_spec
from twodrl_bench.settings import epoch_entry
from twodrl_zoo.hyperparams import PACKAGED, hyperparams_path, load, read_entry


@pytest.mark.parametrize("algo", PACKAGED)
def test_files_are_found_in_the_package(algo: str) -> None:
    path = hyperparams_path(algo)
    assert path.is_file() and path.parent == Path(twodrl_zoo.__file__).parent / "hyperparams"
    assert read_entry(path, "NomadOffice-v0")["gamma"] == 0.9


@pytest.mark.parametrize("algo", ["a2c", "twoda2c"])
def test_every_nomad_id_has_its_own_entry_in_the_protocol_files(algo: str) -> None:
    for env_id in (k for k in gym.registry if k.startswith("NomadOffice")):
        assert read_entry(hyperparams_path(algo), env_id)["n_envs"] == 64, env_id


def test_an_unknown_env_or_algo_is_an_error_naming_it() -> None:
    with pytest.raises(ValueError, match=r"a2c\.yml has no entry for 'CartPole-v0'"):
        epoch_entry(hyperparams_path("a2c"), "CartPole-v0")
    with pytest.raises(ValueError, match=r"ToyNav-v0"):
        Experiment.from_spec({**load_spec("quick_preset"), "env": "ToyNav-v0"})
    with pytest.raises(ValueError, match=r"dqn\.yml' does not exist"):
        hyperparams_path("dqn")


def test_another_folder_is_read_when_given(tmp_path: Path) -> None:
    (tmp_path / "a2c.yml").write_text("ToyNav-v0:\n  n_envs: 3\n  n_timesteps: 100\n")
    assert epoch_entry(hyperparams_path("a2c", tmp_path), "ToyNav-v0") == {"n_envs": 3}


def _entries() -> list[tuple[str, str]]:
    import yaml

    return [(algo, env_id) for algo in PACKAGED for env_id in yaml.safe_load(hyperparams_path(algo).read_text())]


@pytest.mark.parametrize(("algo", "env_id"), _entries())
def test_load_gives_what_rl_zoo3_passes_to_the_constructor(algo: str, env_id: str, tmp_path: Path) -> None:
    """``load`` splits an entry as rl-zoo3's ExperimentManager does (schedules compared at three progress points)."""
    import argparse

    pytest.importorskip("rl_zoo3")
    from rl_zoo3.exp_manager import ExperimentManager

    from twodrl_zoo.zoo import register_zoo

    register_zoo()
    manager = ExperimentManager(argparse.Namespace(), algo, env_id, str(tmp_path), config=str(hyperparams_path(algo)))
    zoo_kwargs, _ = manager.read_hyperparameters()
    zoo_kwargs, _, zoo_callbacks, _ = manager._preprocess_hyperparams(zoo_kwargs)
    hp = load(algo, env_id)
    assert (hp.policy, hp.n_envs, hp.n_timesteps) == (zoo_kwargs.pop("policy"), manager.n_envs, manager.n_timesteps)
    assert hp.normalize == (manager.normalize_kwargs if manager.normalize else None)
    assert sorted(hp.kwargs) == sorted(zoo_kwargs)
    for key, value in hp.kwargs.items():
        if callable(value):
            assert [value(p) for p in (1.0, 0.5, 0.0)] == pytest.approx([zoo_kwargs[key](p) for p in (1.0, 0.5, 0.0)])
        elif callable(zoo_kwargs[key]):  # rl-zoo3 wraps a constant in ConstantSchedule
            assert zoo_kwargs[key](0.5) == value, key
        else:
            assert value == zoo_kwargs[key], key
    assert [type(c) for c in hp.callbacks()] == [type(c) for c in zoo_callbacks]


def test_load_gives_the_arguments_of_a_model() -> None:
    from stable_baselines3.common.env_util import make_vec_env

    hp = load("twoda2c", "NomadOffice-v0")
    assert (hp.n_envs, hp.kwargs["learning_rate"], hp.kwargs["ent_coef"], hp.normalize) == (64, 3e-3, 0.05, None)
    model = sb3_twodrl.TwoDimA2C(hp.policy, make_vec_env("NomadOffice-v0", n_envs=2), **hp.kwargs)
    assert (model.gamma, model.punishment_gamma, model.n_steps) == (0.9, 0.1, 5)
    first, second = hp.callbacks(), hp.callbacks()
    assert isinstance(first[0], sb3_twodrl.NavigationMetricsCallback) and first[0] is not second[0]


def test_load_evaluates_policy_kwargs_schedules_and_normalize() -> None:
    hp = load("twoda2c", "Pendulum-v1")
    assert hp.kwargs["policy_kwargs"] == {"log_std_init": -2, "ortho_init": False}
    assert hp.kwargs["learning_rate"](1.0) == pytest.approx(7e-4) and hp.kwargs["learning_rate"](0.5) == 3.5e-4
    assert hp.normalize == {"gamma": 0.9} and hp.callback == ()
    assert load("twodppo", "Acrobot-v1").normalize == {"norm_obs": True, "norm_reward": False, "gamma": 0.99}


def test_load_names_the_unknown_algo_or_env_and_what_exists(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"algo 'dqn' has no packaged hyperparameters \(packaged: a2c, ppo, twoda2c"):
        load("dqn", "NomadOffice-v0")
    with pytest.raises(ValueError, match=r"twoda2c\.yml has no entry for 'Nomad-v0' \(its entries: NomadOffice-v0, "):
        load("twoda2c", "Nomad-v0")
    (tmp_path / "a2c.yml").write_text("ToyNav-v0:\n  n_timesteps: 100\n  learning_rate: cos_1e-3\n")
    with pytest.raises(ValueError, match=r"learning_rate: unknown schedule 'cos_1e-3'"):
        load("a2c", "ToyNav-v0", tmp_path)
    (tmp_path / "a2c.yml").write_text("ToyNav-v0:\n  n_timesteps: 100\n  frame_stack: 4\n")
    with pytest.raises(ValueError, match=r"frame_stack is applied by rl-zoo3 only"):
        load("a2c", "ToyNav-v0", tmp_path)
