"""The protocol's hyperparameters ship in the package and are found there; an env without an entry is an error."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import pytest

import envs  # noqa: F401  (registers the Nomad office ids)
import sb3_twodrl
from sb3_twodrl.hyperparams import PACKAGED, hyperparams_path, read_entry
from twodrl_bench import load_hyperparams, load_spec, resolve


@pytest.mark.parametrize("algo", PACKAGED)
def test_files_are_found_in_the_package(algo: str) -> None:
    path = hyperparams_path(algo)
    assert path.is_file() and path.parent == Path(sb3_twodrl.__file__).parent / "hyperparams"
    assert read_entry(path, "NomadOffice-v0")["gamma"] == 0.9


@pytest.mark.parametrize("algo", ["a2c", "twoda2c"])
def test_every_nomad_id_has_its_own_entry_in_the_protocol_files(algo: str) -> None:
    for env_id in (k for k in gym.registry if k.startswith("NomadOffice")):
        assert read_entry(hyperparams_path(algo), env_id)["n_envs"] == 64, env_id


def test_an_unknown_env_or_algo_is_an_error_naming_it() -> None:
    with pytest.raises(ValueError, match=r"a2c\.yml has no entry for 'CartPole-v0'"):
        load_hyperparams(hyperparams_path("a2c"), "CartPole-v0")
    with pytest.raises(ValueError, match=r"ToyNav-v0"):
        resolve({**load_spec("quick_preset"), "env": "ToyNav-v0"})
    with pytest.raises(ValueError, match=r"dqn\.yml' does not exist"):
        hyperparams_path("dqn")


def test_another_folder_is_read_when_given(tmp_path: Path) -> None:
    (tmp_path / "a2c.yml").write_text("ToyNav-v0:\n  n_envs: 3\n  n_timesteps: 100\n")
    assert load_hyperparams(hyperparams_path("a2c", tmp_path), "ToyNav-v0") == {"n_envs": 3}
