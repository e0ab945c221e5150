"""twodrl_bench: batched == per-env rows, kill-and-resume == uninterrupted rows (epoch jobs), the adapter, bad input."""

from __future__ import annotations

import inspect
import multiprocessing as mp
import os
import signal
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import twodrl_envs  # noqa: F401  (registers the IDs)
from sb3_twodrl import TwoDimA2C
from twodrl_bench import Experiment, Job, VectorEnvAdapter, algo_class, make_train_env
from twodrl_bench import epochs as runner_module
from twodrl_bench.epochs import train
from twodrl_bench.jobs import checkpoint_path, progress_path

ENV = "NomadOffice-v0"
HP = {
    "twoda2c": {"n_envs": 4, "gamma": 0.9, "punishment_gamma": 0.1, "n_steps": 5, "reward_split": "info"},
    "a2c": {"n_envs": 4, "gamma": 0.9, "n_steps": 5},
}


def spec(tmp_path, algo: str, hyperparams: dict[str, Any] | None = None, **protocol: Any) -> Job:
    """The job of ``algo``, seed 3, on its packaged settings with ``hyperparams`` (default :data:`HP`) over them."""
    experiment = Experiment.from_spec(
        {
            "name": "t",
            "env": ENV,
            "protocol": {"epochs": 4, "learn_episodes": 8, "test_episodes": 4, "tensorboard": False, **protocol},
            "seeds": [3],
            "arms": {algo: {"algo": algo, "override": HP[algo] if hyperparams is None else hyperparams}},
            "report": "paper",
        }
    )
    (job,) = experiment.jobs(tmp_path)
    return job


def without_wall(rows: list[dict]) -> list[dict]:
    """The rows without their wall time, NaN (a share of no labelled episode) written as "nan" so rows compare."""
    return [{k: "nan" if v != v else v for k, v in row.items() if k != "wall_s"} for row in rows]


@pytest.mark.parametrize("algo", ["twoda2c", "a2c"])
def test_batched_pipeline_gives_the_per_env_rows(tmp_path, algo):
    batched = train(spec(tmp_path / "batched", algo, vec_env="batched"))
    per_env = train(spec(tmp_path / "dummy", algo, vec_env="dummy"))
    assert len(batched) == 4 and [r["learn_episodes"] for r in batched] == [8, 16, 24, 32]
    assert without_wall(batched) == without_wall(per_env)


def _run_and_die(s: Job, die_at_epoch: int) -> None:
    """Worker that is killed (SIGKILL, no clean-up) when it starts the test trials of ``die_at_epoch``."""
    original, calls = runner_module.run_test_trials, []

    def dying(*args, **kwargs):
        calls.append(1)
        if len(calls) == die_at_epoch:
            os.kill(os.getpid(), signal.SIGKILL)
        return original(*args, **kwargs)

    runner_module.run_test_trials = dying
    train(s)


@pytest.mark.parametrize("algo", ["twoda2c", "a2c"])
def test_a_killed_run_resumes_with_the_uninterrupted_rows(tmp_path, algo):
    uninterrupted = train(spec(tmp_path / "whole", algo, checkpoint_every=2))
    killed = spec(tmp_path / "killed", algo, checkpoint_every=2)
    worker = mp.get_context("spawn").Process(target=_run_and_die, args=(killed, 4))
    worker.start()
    worker.join(120)
    assert worker.exitcode == -signal.SIGKILL
    assert checkpoint_path(killed.out_dir, killed.name).exists()
    assert progress_path(killed.out_dir, killed.name).read_text().split() == ["1", "2", "3"]
    resumed = train(killed)
    assert without_wall(resumed) == without_wall(uninterrupted)
    model = algo_class(algo).load(tmp_path / "killed" / "models" / f"{algo}_seed3.zip")
    assert model.num_timesteps >= resumed[-1]["env_steps"]


@pytest.mark.parametrize("algo", ["twoda2c", "a2c"])
def test_a_shorter_runs_checkpoint_extends_to_the_longer_runs_rows(tmp_path, algo):
    """A run extended from a shorter run's checkpoint (results/factorial/preregistration.md, amendment 7) gives the
    longer run's rows."""
    longer = train(spec(tmp_path / "whole", algo, checkpoint_every=1))
    s = spec(tmp_path / "extended", algo, checkpoint_every=1)
    assert len(train(spec(tmp_path / "extended", algo, checkpoint_every=1, epochs=2))) == 2  # its checkpoint of epoch 1
    assert without_wall(train(s)) == without_wall(longer)


@pytest.mark.parametrize("algo", ["twoda2c", "a2c"])
def test_a_run_with_policy_kwargs_resumes(tmp_path, algo):
    """SB3's A2C writes its optimizer into ``policy_kwargs``; the spec must keep its own, or the
    checkpoint's protocol would differ from the one that resumes it."""
    hp = {**HP[algo], "policy_kwargs": {"net_arch": [8]}}
    s = spec(tmp_path, algo, hp, checkpoint_every=1)
    assert len(train(spec(tmp_path, algo, hp, checkpoint_every=1, epochs=2))) == 2
    assert s.arm.hyperparams["policy_kwargs"] == {"net_arch": [8]}
    assert len(train(s)) == 4


def test_checkpoint_of_another_protocol_is_refused(tmp_path):
    s = spec(tmp_path, "a2c", checkpoint_every=1)
    train(s)
    with pytest.raises(ValueError, match=r"another run .*protocol\.learn_episodes: 8 != 9"):
        train(spec(tmp_path, "a2c", checkpoint_every=1, learn_episodes=9))


def test_checkpoint_made_under_other_class_defaults_is_refused(tmp_path, monkeypatch):
    """A run resumed after a release changed a default it relied on would mix two algorithms' rows."""
    s = spec(tmp_path, "twoda2c", checkpoint_every=1, epochs=2)
    train(s)  # checkpoints epoch 1
    assert s.arm.defaults["interest_coef"] == repr(inspect.signature(TwoDimA2C).parameters["interest_coef"].default)
    assert "gamma" not in s.arm.defaults  # set by the hyperparameters
    signature = inspect.signature(TwoDimA2C.__init__)
    changed = [p.replace(default=0.25) if p.name == "min_temperature" else p for p in signature.parameters.values()]
    monkeypatch.setattr(TwoDimA2C.__init__, "__signature__", signature.replace(parameters=changed), raising=False)
    with pytest.raises(ValueError, match=r"another run .*defaults\.min_temperature"):
        train(spec(tmp_path, "twoda2c", checkpoint_every=1))


def test_adapter_splits_masked_infos_and_marks_episode_ends():
    venv = gym.make_vec(ENV, num_envs=3, vectorization_mode="vector_entry_point")
    adapter = VectorEnvAdapter(venv)
    adapter.seed(0)
    obs = adapter.reset()
    assert obs.shape == (3, *venv.single_observation_space.shape)
    infos = adapter._split_infos({"a": np.array([1.0, 2.0, 3.0]), "_a": np.array([True, False, True])})
    assert infos == [{"a": 1.0}, {}, {"a": 3.0}]
    step = {"a": np.array([1, 2, 3]), "_a": np.array([False, True, False]), "xy": np.arange(6).reshape(3, 2)}
    step |= {"route": np.array(["u", None, "w"], dtype=object), "_route": np.ones(3, dtype=bool)}
    expected = [{"xy": [0, 1], "route": "u"}, {"xy": [2, 3], "route": None, "a": 2}, {"xy": [4, 5], "route": "w"}]
    assert adapter._split_infos(step) == expected and type(expected[1]["a"]) is int
    for _ in range(300):
        obs, _, dones, infos = adapter.step(np.zeros(3, dtype=np.int64))  # north until a wall
        if dones.any():
            i = int(np.flatnonzero(dones)[0])
            assert infos[i]["terminal_observation"].shape == obs[i].shape
            assert infos[i]["TimeLimit.truncated"] is False and infos[i]["collision"] is True
            break
    else:
        pytest.fail("no episode ended")


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="same step"):
        VectorEnvAdapter(SyncVectorEnv([lambda: gym.make("CartPole-v1")], autoreset_mode=AutoresetMode.NEXT_STEP))
    with pytest.raises(ValueError, match="vec_env='batched'"):
        make_train_env("CartPole-v1", 2, 0, mode="batched")
    with pytest.raises(ValueError, match="vec_env must be"):
        make_train_env(ENV, 2, 0, mode="fast")
    with pytest.raises(ValueError, match="algo must be one of"):
        algo_class("dqn")
    with pytest.raises(ValueError, match=r"protocol\.learn_episodes must be a positive int, got 0"):
        spec("x", "a2c", learn_episodes=0)
    with pytest.raises(ValueError, match=r"protocol\.checkpoint_every must be an int >= 0, got -1"):
        spec("x", "a2c", checkpoint_every=-1)


def test_cartpole_falls_back_to_per_env():
    """CartPole's registered vector env resets on the next step, which SB3 cannot use: auto picks DummyVecEnv."""
    assert type(make_train_env("CartPole-v1", 2, 0)).__name__ == "DummyVecEnv"
    assert type(make_train_env(ENV, 2, 0)) is VectorEnvAdapter
