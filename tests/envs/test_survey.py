"""The survey drive (``sb3-twodrl-survey``): the route covers every reachable cell by lattice moves; the drive's bag
holds what a robot's ``ros2 bag record`` holds, in metres, and imports to the database recorded directly at the same
poses, on SQLite3 and MCAP."""

from __future__ import annotations

import csv
import itertools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("rosbags")

from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from twodrl_envs.analysis.bags import IR_RANGE_M, SONAR_RANGE_M, import_bag, read_bag
from twodrl_envs.analysis.survey import (
    Survey,
    coverage_route,
    drive_survey,
    main,
    survey_database,
    write_survey_bag,
)
from twodrl_envs.memorable.database import SensorDatabase
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.realistic import RealisticModel

MAP = "corridor"  # 189 reachable cells: the smallest shipped map
STILL = RealisticModel(
    scale_bias=0.0,
    scale_sd=0.0,
    misalignment_sd_rad=0.0,
    step_sd_cm=0.0,
    slip_sd_cm=0.0,
    sonar_sd_cm=0.0,
    sonar_sd_frac=0.0,
    sonar_miss_prob=0.0,
    crosstalk_prob=0.0,
    ir_intensity_sd=0.0,
)
"""The artifact model without noise or drift: its readings depend on the pose only."""


@settings(max_examples=6, deadline=None)
@given(st.integers(0, 10_000))
def test_the_route_visits_every_reachable_cell_by_lattice_moves(seed: int) -> None:
    core = office_core(f"generated:S:{seed}")
    route = coverage_route(core)
    assert route[0] == core.start_cell
    assert set(route.tolist()) == set(np.flatnonzero(core.lattice.reachable).tolist())
    assert all(b in core.lattice.moves[a] for a, b in itertools.pairwise(route))
    assert len(route) - 1 < 2 * core.lattice.reachable.sum()  # fewer moves than a depth-first tour's


@pytest.fixture(scope="module")
def survey() -> Survey:
    """The artifact model's survey of the corridor, a reading per cell, with its drift and noise."""
    return drive_survey(MAP, robot="artifact", k=1, seed=3)


def test_every_reachable_cell_gets_its_reading_filed_under_the_true_pose(survey: Survey) -> None:
    lattice = office_core(MAP).lattice
    counts = np.bincount(survey.cell, minlength=len(lattice.cells))
    np.testing.assert_array_equal(counts, lattice.reachable)
    assert survey.skipped == 0 and not survey.misfiled("truth").any()
    assert np.abs(survey.truth_cm[survey.pose_of] - lattice.cells[survey.cell]).max() <= 5.0
    assert survey.odometry_error_cm().max() > 5.0  # the odometry drifts over the drive: why the bag has /amcl_pose


def _same(imported: SensorDatabase, direct: SensorDatabase) -> None:
    np.testing.assert_array_equal(imported.cells, direct.cells)
    np.testing.assert_array_equal(imported.counts, direct.counts)
    np.testing.assert_allclose(imported.ranges_cm, direct.ranges_cm, rtol=0, atol=1e-4)  # the messages' float32


SENSOR_TOPICS = {
    False: {
        **{f"/sonar_{i}": "sensor_msgs/msg/Range" for i in range(16)},
        **{f"/ir_{i}": "sensor_msgs/msg/Range" for i in range(16)},
    },
    True: {"/sonar_scan": "sensor_msgs/msg/LaserScan", "/ir_scan": "sensor_msgs/msg/LaserScan"},
}


@pytest.mark.parametrize(("storage", "scan"), [("sqlite3", False), ("mcap", True)], ids=["range-sqlite3", "scan-mcap"])
def test_the_bag_holds_the_robot_topics_in_metres_and_imports_to_the_direct_database(
    tmp_path: Path, survey: Survey, storage: str, scan: bool
) -> None:
    bag = write_survey_bag(survey, tmp_path / "bag", storage=storage, scan=scan)
    assert f"storage_identifier: {storage}" in (bag / "metadata.yaml").read_text()
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    with AnyReader([bag], default_typestore=typestore) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {
            "/odom": "nav_msgs/msg/Odometry",
            "/amcl_pose": "geometry_msgs/msg/PoseWithCovarianceStamped",
            "/ground_truth": "nav_msgs/msg/Odometry",
            **SENSOR_TOPICS[scan],
        }
        first = {}
        for connection, _, raw in reader.messages():
            if connection.topic not in first:
                first[connection.topic] = reader.deserialize(raw, connection.msgtype)
    assert first["/odom"].header.frame_id == "odom" and first["/amcl_pose"].header.frame_id == "map"
    if scan:
        sonar, ir = first["/sonar_scan"], first["/ir_scan"]
        assert (sonar.header.frame_id, ir.header.frame_id) == ("sonar_ring", "ir_ring")
        assert (sonar.range_min, sonar.range_max) == pytest.approx(SONAR_RANGE_M)
        assert (ir.range_min, ir.range_max) == pytest.approx(IR_RANGE_M)
        assert sonar.angle_increment > 0 and len(sonar.ranges) == 16
        values = np.concatenate([sonar.ranges, ir.ranges])
    else:
        sonar, ir = first["/sonar_3"], first["/ir_3"]
        assert (sonar.header.frame_id, ir.header.frame_id) == ("sonar_3", "ir_3")
        assert (sonar.radiation_type, ir.radiation_type) == (0, 1)  # ULTRASOUND, INFRARED
        assert (sonar.min_range, sonar.max_range) == pytest.approx(SONAR_RANGE_M)
        assert (ir.min_range, ir.max_range) == pytest.approx(IR_RANGE_M)
        values = np.array([sonar.range, ir.range])
    finite = values[np.isfinite(values)]
    assert finite.size and finite.max() <= SONAR_RANGE_M[1]  # metres: no echo beyond the maximum is +inf
    topics = {"sonar": "/sonar_scan", "ir": "/ir_scan"} if scan else {}
    imported = import_bag(bag, map=MAP, pose="/amcl_pose", pose_frame="map", **topics)
    _same(imported, survey_database(survey))
    if not scan:
        positions, _, _ = read_bag(bag, map=MAP)  # /odom, in the odometry frame of the start
        np.testing.assert_allclose(positions, survey.odometry_cm[survey.pose_of], rtol=0, atol=1e-6)


def test_a_survey_without_noise_imports_to_record_databases_recording(tmp_path: Path) -> None:
    """With a model whose readings depend on the pose only, the survey's bag imports to recording.py's direct
    recording (the same readings at the same cells); with noise the draws differ (other keys, other drift)."""
    direct = record_database(2, map=MAP, model=STILL)
    bag = write_survey_bag(drive_survey(MAP, robot="artifact", k=2, model=STILL), tmp_path / "bag")
    _same(import_bag(bag, map=MAP, pose="/amcl_pose", pose_frame="map"), direct)


def test_the_mujoco_robot_surveys_on_the_cells() -> None:
    pytest.importorskip("mujoco")
    survey = drive_survey(MAP, robot="mujoco", k=1)
    lattice = office_core(MAP).lattice
    assert survey.cells == lattice.reachable.sum() and survey.bumps == 0
    assert np.abs(survey.truth_cm[survey.pose_of] - lattice.cells[survey.cell]).max() < 2.0  # the physics keeps on
    assert survey.misfiled("odometry").any()  # its odometry drifts


def test_the_command_reports_progress_and_writes_the_bag_and_the_waypoints(tmp_path: Path, capsys) -> None:
    out, route = tmp_path / "bag", tmp_path / "route.csv"
    main(["--map", MAP, "--robot", "artifact", "--k", "1", "--out", str(out), "--waypoints-out", str(route)])
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("sb3-twodrl-survey: cells ")
    assert "--pose-topic /amcl_pose --pose-frame map" in lines[-2]
    assert (
        lines[-1].startswith("sb3-twodrl-survey: 189 of 189 cells, 189 readings (1 per cell)") and str(out) in lines[-1]
    )
    rows = list(csv.DictReader(route.open()))
    start = office_core(MAP).office.start
    assert (float(rows[0]["x_m"]) * 100, float(rows[0]["y_m"]) * 100) == pytest.approx(start)
    assert sum(int(r["readings"]) for r in rows) == 189


@pytest.mark.parametrize(
    ("argv", "flag"),
    [
        (["--k", "0"], "--k"),
        (["--seed", "-1"], "--seed"),
        (["--robot", "ideal"], "--robot"),
        (["--map", "nowhere.json"], "--map"),
        (["--waypoints-out", "/no_such_dir_for_a_survey/route.csv"], "--waypoints-out"),
    ],
)
def test_bad_flags_are_named(tmp_path: Path, capsys, argv: list[str], flag: str) -> None:
    with pytest.raises(SystemExit):
        main([*argv, "--out", str(tmp_path / "bag")])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert flag in err and not (tmp_path / "bag").exists()


def test_an_existing_bag_is_not_overwritten(tmp_path: Path, capsys) -> None:
    (tmp_path / "bag").mkdir()
    with pytest.raises(SystemExit):
        main(["--map", MAP, "--out", str(tmp_path / "bag")])
    assert "--out" in capsys.readouterr().err


def test_the_mujoco_robot_without_mujoco_says_which_extra(tmp_path: Path, capsys, monkeypatch) -> None:
    from twodrl_envs.nomad import physics

    def missing() -> None:
        raise ModuleNotFoundError(f"{physics.MUJOCO_HINT} (No module named 'mujoco')", name="mujoco")

    monkeypatch.setattr(physics, "import_mujoco", missing)
    with pytest.raises(SystemExit):
        main(["--map", MAP, "--out", str(tmp_path / "bag")])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--robot mujoco" in err and 'pip install "sb3-twodrl[mujoco]"' in err
