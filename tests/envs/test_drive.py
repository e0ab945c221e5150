"""The robot-side loop of docs/own_office.md runs against a stand-in robot (``twodrl_envs.nomad.drive``): readings
in cm in, a move out; an exported policy with the raw input stage reaches the goal on it."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C

import twodrl_envs  # noqa: F401
from tests.helpers.cloned_policy import cloned_model
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.deploy import RawObservation
from twodrl_envs.nomad.drive import StandInRobot
from twodrl_envs.nomad.realistic import RealisticRobot

HAS_MUJOCO = importlib.util.find_spec("mujoco") is not None
IDS = [
    "NomadOffice-v0",
    "NomadOfficeReal-v0",
    pytest.param("NomadOfficeMuJoCo-v0", marks=pytest.mark.skipif(not HAS_MUJOCO, reason="needs mujoco")),
]


@pytest.mark.parametrize("env_id", IDS)
def test_the_raw_readings_give_the_envs_observation(env_id: str) -> None:
    """Through :class:`RawObservation`, the robot's cm readings and odometry are the env's observation, bit for bit,
    move after move; its goal and collision are the env's."""
    robot = StandInRobot(env_id, map="generated:S:3", seed=4)
    env = gym.make(env_id, map="generated:S:3")
    obs, _ = env.reset(seed=4)
    stage = RawObservation("generated:S:3")
    rng = np.random.default_rng(0)
    for _ in range(60):
        raw = np.concatenate([robot.sonar_cm(), robot.ir_cm(), robot.odometry_cm()])[None]
        assert raw.shape == (1, 34) and raw.dtype == np.float64
        np.testing.assert_array_equal(stage(th.as_tensor(raw)).numpy()[0], obs)
        action = int(rng.integers(4))
        robot.move_10cm(action)
        obs, _, terminated, truncated, info = env.step(action)
        assert (robot.at_goal(), robot.collided(), robot.position_cm()) == (
            info["is_success"],
            info["collision"],
            info["position_cm"],
        )
        if terminated or truncated:
            with pytest.raises(RuntimeError, match="the episode has ended"):
                robot.move_10cm(0)
            robot.reset()
            obs, _ = env.reset()
    assert robot.sonar_cm().min() >= 40.0 and robot.ir_cm().max() <= 40.0  # saturated as the robot reports them


def _exported_policy(tmp_path: Path, model: A2C, map_name: str | None, fmt: str) -> Callable[[np.ndarray], int]:
    """The policy as ``sb3-twodrl-export --input-stage NomadOffice-v0`` writes it (raw cm in), and a caller of it:
    ONNX run by onnxruntime as the doc's loop runs it, or TorchScript."""
    from twodrl_zoo.export import deploy_input, export_onnx, export_policy

    stage = deploy_input("NomadOffice-v0", {"map": map_name})
    if fmt == "onnx":
        onnxruntime = pytest.importorskip("onnxruntime")
        pytest.importorskip("onnx")
        session = onnxruntime.InferenceSession(str(export_onnx(model, tmp_path / "policy.onnx", input_stage=stage)))
        return lambda raw: int(session.run(["action"], {"obs": raw})[0][0])
    policy = th.jit.load(str(export_policy(model, tmp_path / "policy.pt", input_stage=stage)))
    return lambda raw: int(policy(th.as_tensor(raw))[0])


@pytest.mark.parametrize(
    ("env_id", "fmt"), [("NomadOfficeReal-v0", "torchscript"), pytest.param(*IDS[2].values, "onnx", marks=IDS[2].marks)]
)
def test_the_docs_robot_loop_reaches_the_goal_on_the_stand_in_robot(tmp_path: Path, env_id: str, fmt: str) -> None:
    core = office_core(None)
    readers = [RealisticRobot(core, None)]
    if HAS_MUJOCO:
        from twodrl_envs.nomad.physics import MuJoCoRobot

        readers.append(MuJoCoRobot(core))
    act = _exported_policy(tmp_path, cloned_model(None, tuple(readers)), None, fmt)
    for seed in (0, 1, 2):
        robot = StandInRobot(env_id, seed=seed)
        sonar_cm, ir_cm, odometry_cm, move_10cm, at_goal = (
            robot.sonar_cm,
            robot.ir_cm,
            robot.odometry_cm,
            robot.move_10cm,
            robot.at_goal,
        )
        while not (at_goal() or robot.collided()):  # the doc's loop
            raw = np.concatenate([sonar_cm(), ir_cm(), odometry_cm()])[None]  # (1, 34) float64
            move_10cm(act(raw))  # 0 north, 1 east, 2 south, 3 west
        assert at_goal(), (env_id, seed, robot.moves, robot.position_cm())
        assert robot.moves < 60


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda: StandInRobot("CartPole-v9"), ValueError, r"env_id must be a registered Nomad env ID .*'CartPole-v9'"),
        (lambda: StandInRobot("CliffWalkingSplit-v1"), ValueError, r"'CliffWalkingSplit-v1' is not a Nomad env"),
        (lambda: StandInRobot(seed="0"), TypeError, r"seed must be an int or None, got str: '0'"),
        (lambda: StandInRobot(observe_odometry=False), ValueError, r"observe_odometry"),
        (lambda: StandInRobot("NomadOffice-v0").move_10cm(4), ValueError, r"action must be 0 \(N\), .* got 4"),
        (lambda: StandInRobot("NomadOffice-v0").move_10cm(True), ValueError, r"got True"),
    ],
)
def test_bad_arguments_are_errors_naming_them(call, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        call()


def test_the_robot_s_time_limit_is_its_map_s_not_the_paper_s_300() -> None:
    """The docs' loop reads ``robot.time_limit``: on a large office it is the map's (3 times the farthest start),
    and the robot refuses a move past it."""
    robot = StandInRobot("NomadOfficeReal-v0", map="generated:L:2", seed=0)
    farthest = robot._task_facts("NomadOfficeReal-v0", {"map": "generated:L:2"})["farthest_start"]
    assert robot.time_limit == 3 * farthest > gym.registry["NomadOfficeReal-v0"].max_episode_steps == 300
    for step in range(robot.time_limit):  # south, north: shuttles in place, no collision on this map at seed 0
        assert not robot.ended(), step
        robot.move_10cm(0 if step % 2 else 2)
    assert robot.ended() and not robot.at_goal()
    with pytest.raises(RuntimeError):
        robot.move_10cm(0)
