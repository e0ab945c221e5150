"""sb3-twodrl-replay-bag: a bag replayed through an exported policy (ONNX, TorchScript) holds the input bag's messages
and, at each reading's time, the move ``model.predict(obs, deterministic=True)`` picks on the env's observation of
that reading; bad arguments are one-line errors naming the argument."""

from __future__ import annotations

import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch as th

pytest.importorskip("rosbags")
pytest.importorskip("onnxruntime")

import twodrl_envs  # noqa: F401
from sb3_twodrl import TwoDimA2C
from twodrl_envs.analysis.bags import write_bag
from twodrl_envs.nomad.core import office_core
from twodrl_zoo.export import deploy_input, export_onnx, export_policy
from twodrl_zoo.replay import MOVES, main, replay_bag

MAP = "generated:S:3"
N_READINGS = 42  # every 7th lattice cell of MAP
PERIOD_S = 0.5
SCANS = {"sonar": "/sonar_scan", "ir": "/ir_scan"}
FLAGS = ["--sonar-topic", SCANS["sonar"], "--ir-topic", SCANS["ir"]]


@pytest.fixture(scope="module")
def policies(tmp_path_factory) -> tuple[TwoDimA2C, dict[str, Path]]:
    """A TwoDimA2C on ``MAP``, exported with the env's input stage as ONNX and TorchScript, and without it.

    Untrained: its random weights pick different moves at different cells (3 east, 39 south on the drive), where a few
    hundred steps of training make it move one way everywhere, which would not show moves replayed out of order."""
    th.manual_seed(0)
    model = TwoDimA2C("MlpPolicy", gym.make("twodrl_envs:NomadOffice-v0", map=MAP), seed=0, device="cpu")
    folder = tmp_path_factory.mktemp("policies")
    stage = deploy_input("NomadOffice-v0", {"map": MAP})
    paths = {
        "onnx": export_onnx(model, folder / "policy.onnx", input_stage=stage),
        "torchscript": export_policy(model, folder / "policy.pt", input_stage=stage),
        "no-stage": export_policy(model, folder / "plain.pt"),
        "other-stage": export_policy(model, folder / "other.pt", input_stage=TenValues()),
    }
    return model, paths


class TenValues(th.nn.Module):
    """An input stage that takes 10 values, not the robot's 32 ranges and odometry."""

    input_shape = (10,)

    def forward(self, raw: th.Tensor) -> th.Tensor:
        return raw.float().repeat(1, 4)[:, :34]


@pytest.fixture(scope="module")
def drive() -> tuple[np.ndarray, np.ndarray]:
    """A drive over every 7th lattice cell of ``MAP``: the cells and their exact readings, cm."""
    core = office_core(MAP)
    return core.lattice.cells[::7], core.ranges[::7]


@pytest.fixture(scope="module")
def bag(tmp_path_factory, drive) -> Path:
    """The drive as a bag: a ``LaserScan`` per ring and odometry in the frame of the robot's start."""
    return write_bag(tmp_path_factory.mktemp("bag") / "drive", *drive, map=MAP, period_s=PERIOD_S, **SCANS)


def _messages(bag: Path) -> list[tuple[str, int, bytes]]:
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:
        return [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]


def _decoded(bag: Path, topic: str) -> list[tuple[int, object]]:
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:
        wanted = [c for c in reader.connections if c.topic == topic]
        return [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages(connections=wanted)]


@pytest.mark.parametrize("kind", ["onnx", "torchscript"])
def test_the_replayed_moves_are_the_models_on_the_envs_observations(tmp_path: Path, policies, drive, bag, kind) -> None:
    model, paths = policies
    positions, _ = drive
    summary = replay_bag(bag, paths[kind], tmp_path / "out", map=MAP, **SCANS)
    env = gym.make("twodrl_envs:NomadOffice-v0", map=MAP)
    observations = np.stack([env.reset(options={"position": tuple(xy)})[0] for xy in positions])
    expected, _ = model.predict(observations, deterministic=True)
    assert len(set(expected.tolist())) >= 2  # a policy that moves one way only would not test the order
    moves = _decoded(tmp_path / "out", "/policy/action")
    assert [m.data for _, m in moves] == [MOVES[a] for a in expected]
    # each move at the time of the reading's last sensor message: write_bag's two scans 1 us apart after the odometry
    assert [t for t, _ in moves] == [10**9 + round(n * PERIOD_S * 1e9) + 2_000 for n in range(N_READINGS)]
    assert summary["readings"] == N_READINGS
    assert summary["actions"] == {move: int((expected == a).sum()) for a, move in enumerate(MOVES)}
    copied = [m for m in _messages(tmp_path / "out") if not m[0].startswith("/policy/")]
    assert copied == _messages(bag)  # every input message, its time and bytes unchanged


def test_a_policy_without_odometry_gets_the_ranges_alone(tmp_path: Path, drive, bag) -> None:
    th.manual_seed(1)
    env = gym.make("twodrl_envs:NomadOffice-v0", map=MAP, observe_odometry=False)
    model = TwoDimA2C("MlpPolicy", env, seed=1, device="cpu")
    stage = deploy_input("NomadOffice-v0", {"map": MAP, "observe_odometry": False})
    policy = export_policy(model, tmp_path / "ranges.pt", input_stage=stage)
    replay_bag(bag, policy, tmp_path / "out", map=MAP, **SCANS)
    observations = np.stack([env.reset(options={"position": tuple(xy)})[0] for xy in drive[0]])
    expected, _ = model.predict(observations, deterministic=True)
    assert [m.data for _, m in _decoded(tmp_path / "out", "/policy/action")] == [MOVES[a] for a in expected]


@pytest.mark.parametrize("frame", ["start", "map"])
def test_the_arrows_point_along_the_moves_in_the_pose_frame(tmp_path: Path, policies, drive, bag, frame) -> None:
    _, paths = policies
    topics = SCANS
    if frame == "map":  # and 16 + 16 Range topics
        bag, topics = write_bag(tmp_path / "drive", *drive, map=MAP, pose_frame=frame), {}
    replay_bag(bag, paths["onnx"], tmp_path / "out", map=MAP, pose_frame=frame, storage="sqlite3", **topics)
    moves = [m.data for _, m in _decoded(tmp_path / "out", "/policy/action")]
    arrows = [m for _, m in _decoded(tmp_path / "out", "/policy/action_marker")]
    odometry = [m for _, m in _decoded(bag, "/odom")]
    assert len(arrows) == len(moves) == N_READINGS
    # the map's north is +y in the map frame, +x (forward) in the odometry frame of a robot started facing north
    north = (0.0, 1.0) if frame == "map" else (1.0, 0.0)
    east = (north[1], -north[0])
    step = {"north": north, "east": east, "south": (-north[0], -north[1]), "west": (-east[0], -east[1])}
    for move, arrow, odom in zip(moves, arrows, odometry, strict=True):
        yaw = 2 * math.atan2(arrow.pose.orientation.z, arrow.pose.orientation.w)
        assert (math.cos(yaw), math.sin(yaw)) == pytest.approx(step[move], abs=1e-9)
        assert arrow.header.frame_id == odom.header.frame_id
        assert (arrow.pose.position.x, arrow.pose.position.y) == (odom.pose.pose.position.x, odom.pose.pose.position.y)


def test_the_command_prints_a_summary_and_refuses_to_overwrite(tmp_path: Path, policies, bag, capsys) -> None:
    _, paths = policies
    args = [str(bag), str(paths["torchscript"]), "--out", str(tmp_path / "out"), "--map", MAP, *FLAGS]
    main(args)
    out = capsys.readouterr().out
    assert f"replayed {N_READINGS} readings of {bag}" in out and "(torchscript): north " in out
    with pytest.raises(SystemExit):
        main(args)
    assert "--out" in capsys.readouterr().err
    main([*args, "--overwrite", "--action-topic", "/moves"])
    assert {t for t, _, _ in _messages(tmp_path / "out")} >= {"/moves", "/moves_marker"}


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("no-bag", r"bag \S+missing does not exist"),
        ("no-policy", r"POLICY: policy '\S+missing\.onnx' does not exist"),
        ("wrong-format", r"POLICY: policy '\S+policy\.zip': unknown format, expected a file ending in \.onnx"),
        ("no-stage", r"POLICY: policy '\S+plain\.pt' takes the env's observations .* --input-stage ENV_ID"),
        ("other-stage", r"POLICY: policy '\S+other\.pt' takes input 'float32 \(n, 10\)', expected the robot's 32"),
        ("not-a-policy", r"POLICY: policy '\S+junk\.onnx' cannot be loaded as onnx"),
        ("out-exists", r"--out: out '\S+taken' exists; pass overwrite \(--overwrite\)"),
        ("out-not-a-bag", r"--out: out '\S+taken' exists and is no ROS 2 bag"),
        ("out-no-folder", r"--out: out '\S+out': directory '\S+nowhere' does not exist"),
    ],
)
def test_bad_arguments_are_one_line_errors(tmp_path: Path, policies, bag, capsys, case, message) -> None:
    _, paths = policies
    policy, out, extra = str(paths["onnx"]), tmp_path / "out", []
    if case == "no-bag":
        bag = tmp_path / "missing"
    elif case == "no-policy":
        policy = str(tmp_path / "missing.onnx")
    elif case == "wrong-format":
        policy = str(tmp_path / "policy.zip")
        Path(policy).write_bytes(b"")
    elif case in ("no-stage", "other-stage"):
        policy = str(paths[case])
    elif case == "not-a-policy":
        policy = str(tmp_path / "junk.onnx")
        Path(policy).write_text("no graph\n")
    elif case in ("out-exists", "out-not-a-bag"):
        out = tmp_path / "taken"
        out.mkdir()
        extra = ["--overwrite"] if case == "out-not-a-bag" else []
    else:
        out = tmp_path / "nowhere" / "out"
    with pytest.raises(SystemExit) as exit_:
        main([str(bag), policy, "--out", str(out), "--map", MAP, *FLAGS, *extra])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1
    assert re.search(message, err), err
    assert not (tmp_path / "out").exists() or case in ("out-exists", "out-not-a-bag")
