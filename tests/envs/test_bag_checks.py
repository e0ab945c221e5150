"""What the bag import checks in a bag's messages (docs/bags.md): each bad bag is a one-line error naming the topic
(and the command's flag where one fixes it); a clockwise or turned ring scan, a PoseStamped pose and renamed frames
(with --sonar-frame) import to the database of the good bag."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

pytest.importorskip("rosbags")

from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

from twodrl_envs.analysis.bags import (
    ANGLE_TOLERANCE_RAD,
    GROUND_TRUTH_TOPIC,
    INFRARED,
    IR_SCAN_TOPIC,
    SCAN_INCREMENT_RAD,
    SONAR_SCAN_TOPIC,
    import_bag,
    read_bag,
    scan_columns,
    write_bag,
)
from twodrl_envs.analysis.cli import main
from twodrl_envs.memorable.database import CSV_COLUMNS, SensorDatabase, load_database
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.realistic import RealisticModel

MAP = "generated:S:3"
SCANS = {"sonar": SONAR_SCAN_TOPIC, "ir": IR_SCAN_TOPIC}
TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
Edit = Callable[[str, str, Any], tuple[str, str, Any] | None]


@pytest.fixture(scope="module")
def drive() -> tuple[np.ndarray, np.ndarray]:
    """The stand-in robot's recording drive through every reachable cell (1 tour): positions and readings, cm."""
    log: list[tuple[np.ndarray, np.ndarray]] = []
    record_database(1, map=MAP, model=RealisticModel(), seed=0, log=lambda xy, r: log.append((xy, r)))
    return np.concatenate([xy for xy, _ in log]), np.concatenate([r for _, r in log])


@pytest.fixture(scope="module")
def range_bag(tmp_path_factory: pytest.TempPathFactory, drive) -> Path:
    """The drive's first 40 readings (the start cell among them) as Range topics."""
    positions, readings = drive
    return write_bag(tmp_path_factory.mktemp("bags") / "ranges", positions[:40], readings[:40], map=MAP)


@pytest.fixture(scope="module")
def short_bag(tmp_path_factory: pytest.TempPathFactory, drive) -> Path:
    """The drive's first 3 readings as Range topics (enough for an error in a message)."""
    positions, readings = drive
    return write_bag(tmp_path_factory.mktemp("bags") / "short", positions[:3], readings[:3], map=MAP)


@pytest.fixture(scope="module")
def scan_bag(tmp_path_factory: pytest.TempPathFactory, drive) -> tuple[Path, SensorDatabase]:
    """The whole drive as LaserScans, and its database."""
    positions, readings = drive
    bag = write_bag(tmp_path_factory.mktemp("bags") / "scans", positions, readings, map=MAP, **SCANS)
    return bag, import_bag(bag, map=MAP, **SCANS)


def rewrite(bag: Path, out: Path, edit: Edit) -> Path:
    """A copy of ``bag`` whose messages went through ``edit(topic, msgtype, msg)`` (``None`` drops one)."""
    connections: dict[str, Any] = {}
    with AnyReader([bag], default_typestore=TYPESTORE) as reader, Writer(out, version=8) as writer:
        for connection, ns, raw in reader.messages():
            edited = edit(connection.topic, connection.msgtype, reader.deserialize(raw, connection.msgtype))
            if edited is None:
                continue
            topic, msgtype, msg = edited
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TYPESTORE)
            writer.write(connections[topic], ns, TYPESTORE.serialize_cdr(msg, msgtype))
    return out


def on(topic: str, change: Callable[[Any], Any]) -> Edit:
    """An edit that changes the messages of one topic only."""
    return lambda t, kind, msg: (t, kind, change(msg) if t == topic else msg)


def _same(a: SensorDatabase, b: SensorDatabase) -> None:
    np.testing.assert_array_equal(a.counts, b.counts)
    np.testing.assert_array_equal(a.ranges_cm, b.ranges_cm)


def command_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    """The command's error line (asserting exit status 2 and one line on stderr)."""
    with pytest.raises(SystemExit) as exit_:
        main(["--map", MAP, *argv])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1, err
    assert err.startswith("sb3-twodrl-record-database: error: ")
    return err


@pytest.mark.parametrize(("first", "direction"), [(0, -1), (-8, 1), (3, -1)], ids=str)
def test_a_clockwise_or_turned_ring_scan_imports_to_the_same_database(
    tmp_path: Path, scan_bag, first: int, direction: int
) -> None:
    """Range k of the rewritten scan is at angle_min + k * angle_increment: sensor (first + direction * k) mod 16."""
    bag, good = scan_bag
    order = (first + direction * np.arange(16)) % 16

    def turn(topic: str, kind: str, msg: Any) -> tuple[str, str, Any]:
        if topic in SCANS.values():
            msg = dataclasses.replace(
                msg,
                angle_min=first * SCAN_INCREMENT_RAD,
                angle_max=(first + direction * 15) * SCAN_INCREMENT_RAD,
                angle_increment=direction * SCAN_INCREMENT_RAD,
                ranges=msg.ranges[order],
            )
        return topic, kind, msg

    turned = rewrite(bag, tmp_path / "turned", turn)
    _same(import_bag(turned, map=MAP, **SCANS), good)
    mirrored = rewrite(
        bag, tmp_path / "mirrored", on(SONAR_SCAN_TOPIC, lambda m: dataclasses.replace(m, ranges=m.ranges[order]))
    )
    assert not np.array_equal(import_bag(mirrored, map=MAP, **SCANS).ranges_cm, good.ranges_cm)  # the order matters


@given(
    first=st.integers(-16, 16),
    clockwise=st.booleans(),
    jitter=st.floats(-0.9 * ANGLE_TOLERANCE_RAD, 0.9 * ANGLE_TOLERANCE_RAD),
)
def test_each_range_of_a_scan_goes_to_the_sensor_it_points_along(first: int, clockwise: bool, jitter: float) -> None:
    """Range k points along angle_min + k * angle_increment; sensor i along i * 22.5 degrees: the nearest bearing."""
    increment = (-1 if clockwise else 1) * SCAN_INCREMENT_RAD + jitter
    angle_min = first * SCAN_INCREMENT_RAD - jitter
    angles = angle_min + increment * np.arange(16)
    sensors = SCAN_INCREMENT_RAD * np.arange(16)
    nearest = np.argmax(np.cos(angles[:, None] - sensors[None, :]), axis=1)
    np.testing.assert_array_equal(scan_columns("scan", angle_min, increment, 16), nearest)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m: dataclasses.replace(m, ranges=m.ranges[:12]), r"has 12 ranges, expected 16 \(one per sensor\)"),
        (lambda m: dataclasses.replace(m, angle_increment=0.2), r"has angle_increment 0\.2 rad, expected \+-0\.392699"),
        (lambda m: dataclasses.replace(m, angle_min=0.1), r"has angle_min 0\.1 rad, not a multiple of 22\.5 degrees"),
        (
            lambda m: dataclasses.replace(m, header=dataclasses.replace(m.header, frame_id="laser")),
            r"has frame_id 'laser', expected 'sonar_ring' \(.*--sonar-frame",
        ),
    ],
    ids=["count", "increment", "angle-min", "frame"],
)
def test_a_scan_off_the_sensor_layout_is_refused_naming_the_topic(
    tmp_path: Path, scan_bag, change: Callable[[Any], Any], message: str, capsys
) -> None:
    bad = rewrite(scan_bag[0], tmp_path / "bad", on(SONAR_SCAN_TOPIC, change))
    err = command_error(
        capsys,
        [
            "--from-bag",
            str(bad),
            "--out",
            str(tmp_path / "x.npz"),
            "--sonar-topic",
            SONAR_SCAN_TOPIC,
            "--ir-topic",
            IR_SCAN_TOPIC,
        ],
    )
    assert f"--from-bag: bag {bad}: topic '{SONAR_SCAN_TOPIC}' " in err
    assert __import__("re").search(message, err)


def _scale(m: Any, factor: float, limits: bool) -> Any:
    changes: dict[str, Any] = {"range": m.range * factor}
    if limits:
        changes.update(min_range=m.min_range * factor, max_range=m.max_range * factor)
    return dataclasses.replace(m, **changes)


@pytest.mark.parametrize(
    ("topic", "change", "message"),
    [
        ("/sonar_0", lambda m: _scale(m, 100, True), r"declares min_range 40, max_range 600: ranges in centimetres\? "),
        (
            "/sonar_1",
            lambda m: _scale(m, 100, False),
            r"reads \d+(\.\d+)? m, beyond its max_range 6 m: ranges in centimetres\?",
        ),
        ("/ir_7", lambda m: _scale(m, 100, True), r"declares min_range 0, max_range 40: ranges in centimetres\? "),
        (
            "/sonar_2",
            lambda m: dataclasses.replace(m, range=6.5),
            r"reads 6\.5 m, beyond its max_range 6 m \(no echo within max_range is \+inf",
        ),
        ("/sonar_2", lambda m: dataclasses.replace(m, range=-0.5), r"reads -0\.5 m, a negative range"),
        (
            "/sonar_5",
            lambda m: dataclasses.replace(m, radiation_type=INFRARED),
            r"has radiation_type 1 \(INFRARED\), expected 0 \(ULTRASOUND\) for the sonar ring",
        ),
        (
            "/ir_3",
            lambda m: dataclasses.replace(m, min_range=0.4, max_range=6.0),
            r"declares min_range 0\.4, max_range 6; the sensor model's ir reads 0-0\.4 m",
        ),
        (
            "/sonar_4",
            lambda m: dataclasses.replace(m, header=dataclasses.replace(m.header, frame_id="sonar_3")),
            r"has frame_id 'sonar_3', expected 'sonar_4' \(.*--sonar-frame",
        ),
    ],
    ids=[
        "centimetres",
        "readings-in-centimetres",
        "ir-centimetres",
        "beyond-max-range",
        "negative",
        "sonar-declaring-infrared",
        "ir-declaring-sonar-ranges",
        "swapped-frames",
    ],
)
def test_a_range_topic_saying_something_wrong_is_a_one_line_error_naming_it(
    tmp_path: Path, short_bag, topic: str, change: Callable[[Any], Any], message: str, capsys
) -> None:
    bad = rewrite(short_bag, tmp_path / "bad", on(topic, change))
    with pytest.raises(ValueError, match=rf"^bag {bad}: topic '{topic}' {message}"):
        import_bag(bad, map=MAP, require_all_cells=False)
    err = command_error(capsys, ["--from-bag", str(bad), "--out", str(tmp_path / "x.npz"), "--allow-missing"])
    assert f"--from-bag: bag {bad}: topic '{topic}' " in err


def test_frames_named_otherwise_import_with_the_frame_flags(tmp_path: Path, range_bag, capsys) -> None:

    def rename(topic: str, kind: str, msg: Any) -> tuple[str, str, Any]:
        if topic.startswith(("/sonar_", "/ir_")):
            msg = dataclasses.replace(
                msg, header=dataclasses.replace(msg.header, frame_id="base_" + msg.header.frame_id)
            )
        return topic, kind, msg

    renamed = rewrite(range_bag, tmp_path / "renamed", rename)
    argv = ["--from-bag", str(renamed), "--allow-missing", "--out", str(tmp_path / "x.npz")]
    err = command_error(capsys, argv)
    assert "topic '/sonar_0' has frame_id 'base_sonar_0', expected 'sonar_0'" in err and "--sonar-frame" in err
    main(["--map", MAP, *argv, "--sonar-frame", "base_sonar_{i}", "--ir-frame", "base_ir_{i}"])
    _same(load_database(tmp_path / "x.npz"), import_bag(range_bag, map=MAP, require_all_cells=False))


@pytest.mark.parametrize("pose_type", ["geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/PoseWithCovarianceStamped"])
def test_a_pose_topic_of_a_pose_type_replaces_the_odometry(tmp_path: Path, scan_bag, pose_type: str, capsys) -> None:
    """The odometry rewritten as a pose topic (and dropped) imports through --pose-topic to the same database."""
    bag, good = scan_bag
    types = TYPESTORE.types

    def as_pose(topic: str, kind: str, msg: Any) -> tuple[str, str, Any]:
        if topic != "/odom":
            return topic, kind, msg
        if pose_type.endswith("PoseStamped"):
            return "/pose", pose_type, types[pose_type](header=msg.header, pose=msg.pose.pose)
        return "/pose", pose_type, types[pose_type](header=msg.header, pose=msg.pose)

    posed = rewrite(bag, tmp_path / "posed", as_pose)
    scans = ["--sonar-topic", SONAR_SCAN_TOPIC, "--ir-topic", IR_SCAN_TOPIC]
    main(["--map", MAP, "--from-bag", str(posed), *scans, "--pose-topic", "/pose", "--out", str(tmp_path / "p.npz")])
    _same(load_database(tmp_path / "p.npz", office_core(MAP)), good)
    err = command_error(capsys, ["--from-bag", str(posed), *scans, "--out", str(tmp_path / "x.npz")])
    assert "no odometry: no topic '/odom'" in err and "--pose-topic" in err
    err = command_error(
        capsys, ["--from-bag", str(posed), *scans, "--odom-topic", "/pose", "--out", str(tmp_path / "x.npz")]
    )
    assert f"topic '/pose' is {pose_type}, expected nav_msgs/msg/Odometry (--odom-topic" in err


def test_a_partial_drive_names_allow_missing_and_reports_its_coverage(tmp_path: Path, range_bag, capsys) -> None:
    bag = range_bag
    out = tmp_path / "few.npz"
    err = command_error(capsys, ["--from-bag", str(bag), "--out", str(out)])
    assert "reachable cells have no readings (e.g. (" in err and "pass --allow-missing" in err
    assert "require_all_cells" not in err and not out.exists()
    main(["--map", MAP, "--from-bag", str(bag), "--allow-missing", "--out", str(out)])
    db = load_database(out)
    reachable = office_core(MAP).lattice.reachable
    covered = int((db.counts[reachable] > 0).sum())
    lines = capsys.readouterr().out.splitlines()
    report = next(i for i, line in enumerate(lines) if line.startswith("coverage: "))
    assert lines[report].startswith(f"coverage: {covered} of {int(reachable.sum())} reachable cells have readings")
    assert "readings per reachable cell: min 0, median 0, max " in lines[report]
    assert lines[report + 1].startswith(f"  {int(reachable.sum()) - covered} without readings, e.g. (")


def test_a_complete_drive_reports_full_coverage_and_draws_it(tmp_path: Path, scan_bag, capsys) -> None:
    pytest.importorskip("matplotlib")
    bag = scan_bag[0]
    png = tmp_path / "coverage.png"
    main(
        [
            "--map",
            MAP,
            "--from-bag",
            str(bag),
            "--sonar-topic",
            SONAR_SCAN_TOPIC,
            "--ir-topic",
            IR_SCAN_TOPIC,
            "--out",
            str(tmp_path / "db.npz"),
            "--coverage-png",
            str(png),
        ]
    )
    n = int(office_core(MAP).lattice.reachable.sum())
    assert f"coverage: {n} of {n} reachable cells have readings (100%)" in capsys.readouterr().out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_without_matplotlib_the_coverage_picture_names_the_extra(tmp_path: Path) -> None:
    code = (
        "import sys; sys.modules['matplotlib'] = None\n"
        "from twodrl_envs.analysis.cli import main\n"
        f"main(['--from-bag', 'bag', '--out', {str(tmp_path / 'x.npz')!r}, "
        f"'--coverage-png', {str(tmp_path / 'c.png')!r}])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 2 and out.stderr.strip().splitlines()[-1].endswith('pip install "sb3-twodrl[plots]"')


def test_the_ground_truth_topic_gives_the_true_positions(tmp_path: Path, drive) -> None:
    positions, readings = drive
    drifted = positions[:4] + np.array([3.0, -2.0])
    bag = write_bag(tmp_path / "truth", drifted, readings[:4], map=MAP, ground_truth_cm=positions[:4])
    np.testing.assert_allclose(read_bag(bag, map=MAP)[0], drifted, atol=1e-6)
    np.testing.assert_allclose(
        read_bag(bag, map=MAP, pose=GROUND_TRUTH_TOPIC, pose_frame="map")[0], positions[:4], atol=1e-6
    )


def test_a_partial_csv_log_names_allow_missing_too(tmp_path: Path, drive, capsys) -> None:
    positions, readings = drive
    log = tmp_path / "log.csv"
    np.savetxt(
        log, np.hstack([positions[:40], readings[:40]]), delimiter=",", header=",".join(CSV_COLUMNS), comments=""
    )
    err = command_error(capsys, ["--from-csv", str(log), "--out", str(tmp_path / "x.npz")])
    assert f"--from-csv: {log}: " in err and "pass --allow-missing" in err and "require_all_cells" not in err
