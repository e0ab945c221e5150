"""Replay a recorded ROS 2 bag through an exported policy, offline: the policy's move for each reading, as topics.

A policy exported with ``sb3-twodrl-export --input-stage ENV_ID`` (ONNX or TorchScript) takes what the robot
measures: its 32 ranges and its odometry in cm. :func:`replay_bag` reads a bag's readings as the database import
reads them (:func:`~twodrl_envs.analysis.bags.read_bag`: a reading once all 32 sensors have published, at the latest
pose, in the map's frame), runs the policy on them, and writes an output bag holding every message of the input bag
and, at each reading's time (the bag time of the message that completed it), two more messages:

* ``/policy/action``, ``std_msgs/msg/String``: the move's name, ``north``, ``east``, ``south`` or ``west`` (the
  Nomad envs' actions 0-3). A name reads without a legend in Foxglove (Raw Messages, State Transitions) and in
  ``ros2 topic echo``; a number would need one.
* ``/policy/action_marker``, ``visualization_msgs/msg/Marker``: an arrow at the reading's pose, in the pose
  topic's frame, pointing where the move goes; rviz has no display for ``std_msgs``, and in rviz or Foxglove's 3D
  panel the arrows draw the policy's moves along the drive.

The command (``--sonar-topic`` ... ``--pose-frame`` as ``sb3-twodrl-record-database --from-bag`` takes them)::

    sb3-twodrl-replay-bag robot_bag policy.onnx --out robot_bag_replayed --map my_office.json
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.analysis.bags import (
    IR_TOPIC,
    ODOMETRY_TOPIC,
    SONAR_TOPIC,
    STORAGES,
    header,
    import_rosbags,
    read_bag_readings,
)
from twodrl_envs.analysis.cli import add_bag_arguments, bag_options
from twodrl_envs.nomad.core import office_core

MOVES = ("north", "east", "south", "west")  # the Nomad envs' actions 0, 1, 2, 3
ACTION_TOPIC = "/policy/action"
STRING, MARKER = "std_msgs/msg/String", "visualization_msgs/msg/Marker"
SUFFIXES = {".onnx": "onnx", ".pt": "torchscript", ".pth": "torchscript"}
RAW_WIDTHS = (34, 32)  # 32 ranges and the odometry (x, y) in cm; or the ranges alone (observe_odometry=False)
_HEADING = {"map": 0.0, "start": -math.pi / 2}  # the pose frame's yaw of a move east; north is +pi/2 from it
_MOVE_YAW = (math.pi / 2, 0.0, -math.pi / 2, math.pi)  # north, east, south, west in the map's frame (x east)


@dataclass(frozen=True)
class ExportedPolicy:
    """An exported policy with an input stage: raw readings ``(n, width)`` -> actions ``(n,)``."""

    path: Path
    format: str
    width: int
    dtype: str
    module: Any  # an onnxruntime InferenceSession or a TorchScript module

    def act(self, raw: np.ndarray) -> np.ndarray:
        """The policy's actions (int64) for raw readings ``(n, width)``."""
        raw = np.ascontiguousarray(raw, dtype=self.dtype)
        if self.format == "onnx":
            name = self.module.get_inputs()[0].name
            return np.asarray(self.module.run(None, {name: raw})[0], dtype=np.int64)
        import torch

        with torch.no_grad():
            return np.asarray(self.module(torch.from_numpy(raw)).numpy(), dtype=np.int64)


def load_policy(path: str | Path) -> ExportedPolicy:
    """The policy ``sb3-twodrl-export --input-stage`` wrote at ``path`` (``.onnx``: ONNX; ``.pt``, ``.pth``:
    TorchScript).

    :raises ValueError: no such file, another suffix, a file that does not load, a policy exported without an input
        stage or for another input than the robot's 32 ranges (and odometry) in cm, or with other than 4 actions
    """
    path = Path(path)
    kind = SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise ValueError(f"policy {str(path)!r}: unknown format, expected a file ending in {', '.join(SUFFIXES)}")
    if not path.is_file():
        raise ValueError(f"policy {str(path)!r} does not exist")
    try:
        module, meta = _load_onnx(path) if kind == "onnx" else _load_torchscript(path)
    except Exception as err:  # onnxruntime and torch raise their own errors for a file that is no policy
        raise ValueError(f"policy {str(path)!r} cannot be loaded as {kind}: {_one_line(err)}") from err
    if meta is None:
        raise ValueError(f"policy {str(path)!r} has no meta.json: it was not written by sb3-twodrl-export")
    layout = re.fullmatch(r"(\w+) \(n, ([\d, ]*)\)", str(meta.get("input", "")))
    shape = tuple(int(d) for d in layout.group(2).split(",") if d.strip()) if layout else ()
    if not meta.get("input_stage"):
        raise ValueError(
            f"policy {str(path)!r} takes the env's observations ({meta.get('input')}), not the robot's readings in cm: "
            "export it with sb3-twodrl-export MODEL POLICY --input-stage ENV_ID"
        )
    if layout is None or len(shape) != 1 or shape[0] not in RAW_WIDTHS:
        raise ValueError(
            f"policy {str(path)!r} takes input {meta.get('input')!r}, expected the robot's 32 ranges and odometry "
            "in cm, (n, 34), or the ranges alone, (n, 32)"
        )
    if meta.get("n_actions") != len(MOVES):
        raise ValueError(f"policy {str(path)!r} has {meta.get('n_actions')} actions, expected {len(MOVES)} moves")
    return ExportedPolicy(path, kind, shape[0], layout.group(1), module)


def _one_line(err: Exception) -> str:
    return " ".join(f"{type(err).__name__}: {err}".split())[:300]


def _load_onnx(path: Path) -> tuple[Any, dict[str, Any] | None]:
    try:
        import onnxruntime
    except ImportError as err:
        raise ModuleNotFoundError(
            f'an ONNX policy needs onnxruntime: pip install "sb3-twodrl[onnx]" ({err})', name="onnxruntime"
        ) from err
    session = onnxruntime.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    meta = session.get_modelmeta().custom_metadata_map.get("meta.json")
    return session, json.loads(meta) if meta else None


def _load_torchscript(path: Path) -> tuple[Any, dict[str, Any] | None]:
    import torch

    extra = {"meta.json": ""}
    module = torch.jit.load(str(path), map_location="cpu", _extra_files=extra)
    return module.eval(), json.loads(extra["meta.json"]) if extra["meta.json"] else None


def _typestore() -> Any:
    typesys = import_rosbags().typesys
    return typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)


def _marker(typestore: Any, stamp: int, index: int, pose: tuple[str, float, float], action: int, frame: str) -> Any:
    """An arrow at ``pose`` in the pose topic's frame, pointing along the move ``action``."""
    types = typestore.types
    yaw = _MOVE_YAW[action] + _HEADING[frame]
    return types[MARKER](
        header=header(typestore, stamp, pose[0]),
        ns="policy",
        id=index,
        type=0,  # ARROW
        action=0,  # ADD
        pose=types["geometry_msgs/msg/Pose"](
            position=types["geometry_msgs/msg/Point"](x=pose[1], y=pose[2], z=0.0),
            orientation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
        ),
        scale=types["geometry_msgs/msg/Vector3"](x=0.2, y=0.03, z=0.03),
        color=types["std_msgs/msg/ColorRGBA"](r=0.1, g=0.8, b=0.2, a=1.0),
        lifetime=types["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
        frame_locked=False,
        points=[],
        colors=[],
        texture_resource="",
        texture=types["sensor_msgs/msg/CompressedImage"](
            header=header(typestore, 0, ""), format="", data=np.zeros(0, dtype=np.uint8)
        ),
        uv_coordinates=[],
        text="",
        mesh_resource="",
        mesh_file=types["visualization_msgs/msg/MeshFile"](filename="", data=np.zeros(0, dtype=np.uint8)),
        mesh_use_embedded_materials=False,
    )


def _check_out(out: Path, bag: Path, overwrite: bool) -> None:
    if out.resolve() == bag.resolve():
        raise ValueError(f"out {str(out)!r} is the input bag; name another folder")
    if not out.parent.is_dir():
        raise ValueError(f"out {str(out)!r}: directory {str(out.parent)!r} does not exist")
    if out.exists():
        if not overwrite:
            raise ValueError(f"out {str(out)!r} exists; pass overwrite (--overwrite) to replace it")
        if not (out / "metadata.yaml").is_file():
            raise ValueError(f"out {str(out)!r} exists and is no ROS 2 bag (no metadata.yaml); not replaced")


def replay_bag(
    bag: str | Path,
    policy: str | Path | ExportedPolicy,
    out: str | Path,
    *,
    map: str | Path | None = None,
    sonar: str = SONAR_TOPIC,
    ir: str = IR_TOPIC,
    odometry: str = ODOMETRY_TOPIC,
    pose: str | None = None,
    pose_frame: str = "start",
    sonar_frame: str | None = None,
    ir_frame: str | None = None,
    action_topic: str = ACTION_TOPIC,
    storage: str = "mcap",
    overwrite: bool = False,
) -> dict[str, Any]:
    """Write ``out``: the bag ``bag``, plus ``policy``'s move for each of its readings (module docstring); a summary.

    The topics, ``pose_frame`` and the sensors' frame ids are :func:`~twodrl_envs.analysis.bags.read_bag`'s; ``map``
    must be the map the policy was exported for. ``out`` is written in ``storage`` (``"mcap"`` or ``"sqlite3"``); an
    existing ``out`` is replaced only with ``overwrite`` and only if it is a bag. Nothing is written unless the whole
    replay works.

    :raises ValueError: one line naming the bad argument (see :func:`load_policy` and ``read_bag`` for theirs)
    """
    bag, out = Path(bag), Path(out)
    if storage not in STORAGES:
        raise ValueError(f"storage must be one of {STORAGES}, got {storage!r}")
    if not isinstance(action_topic, str) or not re.fullmatch(r"(/[A-Za-z_][\w]*)+", action_topic):
        raise ValueError(f"action topic must be a topic name such as {ACTION_TOPIC!r}, got {action_topic!r}")
    _check_out(out, bag, overwrite)
    exported = policy if isinstance(policy, ExportedPolicy) else load_policy(policy)
    read = read_bag_readings(
        bag,
        map=map,
        sonar=sonar,
        ir=ir,
        odometry=odometry,
        pose=pose,
        pose_frame=pose_frame,
        sonar_frame=sonar_frame,
        ir_frame=ir_frame,
    )
    raw = np.concatenate([read.readings, read.positions], axis=1) if exported.width == 34 else read.readings
    actions = exported.act(raw)
    if actions.shape != (len(raw),) or not np.isin(actions, range(len(MOVES))).all():
        raise ValueError(f"policy {str(exported.path)!r} gave actions outside 0-3 (or of shape {actions.shape})")
    stamps, poses, stats = read.stamps, read.poses, read.stats
    partial = out.parent / f".{out.name}.partial"
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir()
    try:
        copied = _write(bag, partial / out.name, storage, action_topic, stamps, poses, actions, pose_frame)
        if out.exists():
            shutil.rmtree(out)
        (partial / out.name).rename(out)
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    counts = Counter(MOVES[a] for a in actions.tolist())
    return {
        "readings": len(actions),
        "readings_before_first_pose": stats["readings_before_first_pose"],
        "actions": {move: counts[move] for move in MOVES},
        "copied": copied,
        "out": out,
        "topics": (action_topic, f"{action_topic}_marker"),
    }


def _write(
    bag: Path,
    out: Path,
    storage: str,
    topic: str,
    stamps: list[int],
    poses: list[tuple[str, float, float]],
    actions: np.ndarray,
    pose_frame: str,
) -> int:
    """Copy every message of ``bag`` to a new bag ``out``, each reading's action after the message completing it."""
    rosbags = import_rosbags()
    typestore = _typestore()
    types = typestore.types
    plugin = rosbags.rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbags.rosbag2.StoragePlugin.SQLITE3
    copied = 0
    with (
        rosbags.highlevel.AnyReader([bag], default_typestore=typestore) as reader,
        rosbags.rosbag2.Writer(out, version=8, storage_plugin=plugin) as writer,
    ):
        if not reader.is2:
            raise ValueError(f"bag {bag} is a ROS 1 bag; convert it first (rosbags-convert --src BAG --dst OUT)")
        targets: dict[int, Any] = {}
        for c in reader.connections:
            same = [w for w in writer.connections if (w.topic, w.msgtype, w.ext) == (c.topic, c.msgtype, c.ext)]
            known = {"msgdef": c.msgdef.data, "rihs01": c.digest} if c.msgdef.data and c.digest else {}
            targets[c.id] = (
                same[0]
                if same
                else writer.add_connection(
                    c.topic,
                    c.msgtype,
                    typestore=reader.typestore,
                    serialization_format=c.ext.serialization_format,
                    offered_qos_profiles=c.ext.offered_qos_profiles,
                    **known,
                )
            )
        if any(w.topic in (topic, f"{topic}_marker") for w in writer.connections):
            raise ValueError(f"bag {bag} has a topic {topic!r} (or its _marker) already; pick another action topic")
        names = writer.add_connection(topic, STRING, typestore=typestore)
        arrows = writer.add_connection(f"{topic}_marker", MARKER, typestore=typestore)
        k = 0
        for connection, stamp, raw in reader.messages():
            writer.write(targets[connection.id], stamp, raw)
            copied += 1
            while k < len(stamps) and stamps[k] <= stamp:
                action = int(actions[k])
                writer.write(names, stamps[k], typestore.serialize_cdr(types[STRING](data=MOVES[action]), STRING))
                marker = _marker(typestore, stamps[k], k, poses[k], action, pose_frame)
                writer.write(arrows, stamps[k], typestore.serialize_cdr(marker, MARKER))
                k += 1
    return copied


HELP = """Replay a ROS 2 bag through an exported policy, offline: the policy's move for each reading, as new topics.

POLICY is a policy exported with sb3-twodrl-export --input-stage ENV_ID (.onnx: ONNX, needs pip install
"sb3-twodrl[onnx]"; .pt/.pth: TorchScript), which takes the robot's 32 ranges and odometry in cm. The bag's readings
are read as sb3-twodrl-record-database --from-bag reads them (the same topic options; needs pip install
"sb3-twodrl[ros]"). OUT gets every message of the bag and, at each reading's time, the policy's move on
--action-topic (std_msgs/msg/String: north, east, south or west) and an arrow on --action-topic + "_marker"
(visualization_msgs/msg/Marker, in the pose topic's frame), to inspect in Foxglove or rviz before driving.

    sb3-twodrl-replay-bag robot_bag policy.onnx --out robot_bag_replayed --map my_office.json
"""


def main(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-replay-bag`` (:data:`HELP`)."""
    parser = argparse.ArgumentParser(
        prog="sb3-twodrl-replay-bag", description=HELP, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("bag", type=Path, metavar="BAG", help="the ROS 2 bag to replay (folder or file)")
    parser.add_argument("policy", type=Path, metavar="POLICY", help="exported policy, .onnx or .pt (--input-stage)")
    parser.add_argument("--out", type=Path, required=True, help="the bag to write (a new folder)")
    parser.add_argument("--overwrite", action="store_true", help="replace --out if it is a bag already")
    parser.add_argument("--map", default=None, help="the map the policy was exported for (default: office)")
    add_bag_arguments(parser)
    parser.add_argument("--action-topic", default=ACTION_TOPIC, help=f"the moves' topic (default {ACTION_TOPIC})")
    parser.add_argument("--storage", choices=STORAGES, default="mcap", help="--out's storage (default mcap)")
    args = parser.parse_args(argv)
    try:
        office_core(args.map)
    except (ValueError, TypeError) as err:
        parser.exit(2, f"{parser.prog}: error: --map: {err}\n")
    try:
        exported = load_policy(args.policy)
    except (ValueError, ModuleNotFoundError) as err:
        parser.exit(2, f"{parser.prog}: error: POLICY: {err}\n")
    try:
        _check_out(args.out, args.bag, args.overwrite)
    except ValueError as err:
        parser.exit(2, f"{parser.prog}: error: --out: {err}\n")
    try:
        summary = replay_bag(
            args.bag,
            exported,
            args.out,
            map=args.map,
            action_topic=args.action_topic,
            storage=args.storage,
            overwrite=args.overwrite,
            **bag_options(args),
        )
    except (ValueError, ModuleNotFoundError) as err:  # each names the bag, or the flag of what is wrong with it
        parser.exit(2, f"{parser.prog}: error: {err}\n")
    counts = ", ".join(f"{move} {n}" for move, n in summary["actions"].items())
    skipped = summary["readings_before_first_pose"]
    print(
        f"replayed {summary['readings']} readings of {args.bag} through {args.policy} ({exported.format})"
        + (f", {skipped} before the first pose skipped" if skipped else "")
        + f": {counts}\nwrote {summary['out']}: {summary['copied']} messages copied, "
        f"{summary['readings']} moves on {summary['topics'][0]} and arrows on {summary['topics'][1]}"
    )


if __name__ == "__main__":
    main()
