"""Recordings from ROS 2 bags: a drive of the stand-in robot written as a bag (``rosbags``) imports to the database
recorded directly; a bag without a topic, with a wrong message type or without odometry is a one-line error."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from twodrl_envs.analysis.bags import import_bag, read_bag, write_bag
from twodrl_envs.analysis.cli import main
from twodrl_envs.memorable.database import SensorDatabase, load_database
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.realistic import RealisticModel

MAP = "generated:S:3"


@pytest.fixture(scope="module")
def drive() -> tuple[SensorDatabase, np.ndarray, np.ndarray]:
    """The database the stand-in robot records directly (2 tours) and its drive: positions and readings, cm."""
    log: list[tuple[np.ndarray, np.ndarray]] = []
    direct = record_database(2, map=MAP, model=RealisticModel(), seed=0, log=lambda xy, r: log.append((xy, r)))
    return direct, np.concatenate([xy for xy, _ in log]), np.concatenate([r for _, r in log])


def _same(imported: SensorDatabase, direct: SensorDatabase) -> None:
    np.testing.assert_array_equal(imported.cells, direct.cells)
    np.testing.assert_array_equal(imported.counts, direct.counts)
    np.testing.assert_allclose(imported.ranges_cm, direct.ranges_cm, rtol=0, atol=1e-4)  # the messages' float32
    assert imported.metadata["map_sha256"] == direct.metadata["map_sha256"]


@pytest.mark.parametrize(
    ("topics", "pose_frame", "storage"),
    [({}, "start", "sqlite3"), ({"sonar": "/sonar_scan", "ir": "/ir_scan"}, "map", "mcap")],
    ids=["range-topics-odometry-frame-sqlite", "laserscans-map-frame-mcap"],
)
def test_the_bag_round_trip_equals_the_direct_recording(
    tmp_path: Path, drive, topics: dict, pose_frame: str, storage: str
) -> None:
    direct, positions, readings = drive
    bag = write_bag(tmp_path / "drive", positions, readings, map=MAP, pose_frame=pose_frame, storage=storage, **topics)
    imported = import_bag(bag, map=MAP, pose_frame=pose_frame, **topics)
    _same(imported, direct)
    assert imported.metadata["recording"]["source"] == "ros2 bag"
    assert imported.metadata["recording"]["readings"] == len(readings)


def test_the_command_imports_a_bag(tmp_path: Path, drive, capsys) -> None:
    direct, positions, readings = drive
    bag = write_bag(tmp_path / "drive", positions, readings, map=MAP)
    main(["--map", MAP, "--from-bag", str(bag), "--out", str(tmp_path / "db.npz")])
    _same(load_database(tmp_path / "db.npz", office_core(MAP)), direct)
    assert f"wrote {tmp_path / 'db.npz'}" in capsys.readouterr().out
    main(["--map", MAP, "--from-bag", str(bag), "--k", "1", "--out", str(tmp_path / "k1.npz")])
    first = load_database(tmp_path / "k1.npz")
    np.testing.assert_array_equal(first.counts, np.minimum(direct.counts, 1))
    np.testing.assert_allclose(first.ranges_cm, direct.ranges_cm[direct.offsets[direct.counts > 0]], atol=1e-4)


def test_read_bag_gives_the_drives_positions_and_missing_cells_are_reported(tmp_path: Path, drive) -> None:
    _, positions, readings = drive
    bag = write_bag(tmp_path / "few", positions[:5], readings[:5], map=MAP)
    xy, ranges, stats = read_bag(bag, map=MAP)
    np.testing.assert_allclose(xy, positions[:5], atol=1e-6)
    assert ranges.shape == (5, 32) and stats == {"readings": 5, "readings_before_first_pose": 0, "poses": 5}
    with pytest.raises(ValueError, match=r"reachable cells have no readings \(e\.g\. "):
        import_bag(bag, map=MAP)
    assert import_bag(bag, map=MAP, require_all_cells=False).counts.sum() == 5


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"ir": "/infrared_{i}"}, r"no topic '/infrared_0' \(its topics: /ir_0, "),
        ({"sonar": "/odom"}, r"topic '/odom' is nav_msgs/msg/Odometry, expected sensor_msgs/msg/LaserScan"),
        ({"ir": "/sonar_{i}", "sonar": "/ir_{i}", "pose": "/sonar_3"}, r"topic '/sonar_3' is sensor_msgs/msg/Range, "),
        ({"odometry": "/wheel_odom"}, r"no odometry: no topic '/wheel_odom'"),
    ],
    ids=["missing-topic", "wrong-type", "wrong-pose-type", "no-odometry"],
)
def test_a_bad_bag_is_a_one_line_error_naming_it(tmp_path: Path, drive, options: dict, message: str, capsys) -> None:
    _, positions, readings = drive
    bag = write_bag(tmp_path / "drive", positions[:3], readings[:3], map=MAP)
    with pytest.raises(ValueError, match=message):
        import_bag(bag, map=MAP, **options)
    flags = {"sonar": "--sonar-topic", "ir": "--ir-topic", "odometry": "--odom-topic", "pose": "--pose-topic"}
    argv = [arg for key, value in options.items() for arg in (flags[key], value)]
    with pytest.raises(SystemExit) as exit_:
        main(["--map", MAP, "--from-bag", str(bag), "--out", str(tmp_path / "x.npz"), *argv])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and err.startswith("sb3-twodrl-record-database: error: ")


def test_a_bag_whose_odometry_topic_is_silent(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "silent", np.zeros((0, 2)), np.zeros((0, 32)), map=MAP)
    with pytest.raises(ValueError, match=r"no odometry: topic '/odom' has no messages"):
        import_bag(bag, map=MAP)
    with pytest.raises(ValueError, match=r"bag .*nowhere does not exist"):
        import_bag(tmp_path / "nowhere", map=MAP)


@pytest.mark.parametrize(
    ("options", "error", "message"),
    [
        ({"pose_frame": "odom"}, ValueError, r"pose_frame must be one of \('start', 'map'\), got 'odom'"),
        ({"sonar": "sonar_{i}"}, ValueError, r"sonar topic must be a topic name starting with '/', got 'sonar_\{i\}'"),
        ({"per_cell": 0}, ValueError, r"per_cell must be a positive int or None, got 0"),
    ],
)
def test_bad_arguments_are_errors_naming_them(tmp_path: Path, drive, options: dict, error: type, message: str) -> None:
    _, positions, readings = drive
    bag = write_bag(tmp_path / "drive", positions[:3], readings[:3], map=MAP)
    with pytest.raises(error, match=message):
        import_bag(bag, map=MAP, require_all_cells=False, **options)


def test_write_bag_names_a_bad_period(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"period_s must be a number of seconds from 0.001, got 0"):
        write_bag(tmp_path / "b", np.zeros((1, 2)), np.full((1, 32), 40.0), map=MAP, period_s=0)


def test_without_rosbags_the_command_names_the_extra(tmp_path: Path) -> None:
    code = (
        "import sys; sys.modules['rosbags'] = None\n"
        "from twodrl_envs.analysis.cli import main\n"
        f"main(['--from-bag', {str(tmp_path / 'bag')!r}, '--out', {str(tmp_path / 'x.npz')!r}])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    last = out.stderr.strip().splitlines()[-1]
    assert out.returncode == 2 and 'pip install "sb3-twodrl[ros]"' in last and out.stderr.count("\n") == 1
