"""Geometry and sensors against hand-computed values; map-file validation."""

import json
import math
import os

import numpy as np
import pytest

from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.geometry import ROBOT_RADIUS_CM, swept_clearance
from twodrl_envs.nomad.maps import load_map
from twodrl_envs.nomad.sensors import NoiseModel, exact_ranges, normalise, realistic_readings

OFFICE = load_map()


def sensor_at(centre, k):
    """Position of sensor k (k * 22.5 degrees counter-clockwise from north) on the 30 cm body."""
    angle = math.radians(22.5 * k)
    return centre[0] - 30 * math.sin(angle), centre[1] + 30 * math.cos(angle)


def test_axis_readings_at_start():
    ranges = exact_ranges(OFFICE, np.array([[60.0, 85.0]]))[0]
    # sonar 0 north: top wall y=305 from sensor (60, 115); 4 west: x=0 from (30, 85); 8 south: floor
    # from (60, 55); 12 east: along the bent passage to x=290 from (90, 85) (its corners outside the cone)
    for k, expected in {0: 190.0, 4: 30.0, 8: 55.0, 12: 200.0}.items():
        assert ranges[k] == pytest.approx(expected, abs=1.0)
        assert ranges[16 + k] == pytest.approx(expected, abs=1.0)  # IR beam, same axis
    obs = normalise(ranges)
    assert obs[4] == 0.0  # sonar below 40 cm saturates at its minimum
    assert obs[16 + 4] == pytest.approx(30 / 40)  # IR within range
    assert obs[16 + 8] == 1.0  # IR beyond 40 cm saturates


def test_oblique_readings_see_block_top_inside_cone():
    centre = (110.0, 210.0)
    sx, sy = sensor_at(centre, 10)  # facing south-east (225 degrees counter-clockwise from north)
    drop = sy - 155.0  # height above the partition's top face y = 155, x in [120, 210]
    # nearest cone point is where the cone's south-most edge (22.5 + 11.25 degrees off south) meets the face
    sonar = drop / math.cos(math.radians(45 - 11.25))
    ir = drop / math.cos(math.radians(45))  # beam along the axis
    assert 120 < sx + drop * math.tan(math.radians(45 - 11.25)) < 210
    assert 120 < sx + drop < 210
    ranges = exact_ranges(OFFICE, np.array([centre]))[0]
    assert ranges[10] == pytest.approx(sonar, abs=1.0)
    assert ranges[26] == pytest.approx(ir, abs=1.0)


def test_swept_disc_touching_counts_as_collision():
    walls = OFFICE.walls
    into_floor = swept_clearance(np.array([[60.0, 40.0]]), np.array([[60.0, 30.0]]), walls)
    along_floor = swept_clearance(np.array([[60.0, 31.0]]), np.array([[70.0, 31.0]]), walls)
    assert into_floor[0] <= ROBOT_RADIUS_CM
    assert along_floor[0] == pytest.approx(31.0)
    # a wall tip between the two ends: both end discs clear (30.2 cm), the swept disc does not (29.8 cm)
    tip = np.array([[5.0, 29.8, 5.0, 100.0]])
    assert swept_clearance(np.array([[0.0, 0.0]]), np.array([[0.0, 0.0]]), tip)[0] > ROBOT_RADIUS_CM
    assert swept_clearance(np.array([[0.0, 0.0]]), np.array([[10.0, 0.0]]), tip)[0] == pytest.approx(29.8)


def write_map(tmp_path, **changes):
    data = json.loads(open(OFFICE.source).read())
    data.update(changes)
    path = tmp_path / "office.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"bounds": [0, 0, 330]}, "bounds"),
        ({"walls": [[0, 0, 10]]}, r"walls\[0\]"),
        ({"walls": [[5, 5, 5, 5]]}, "zero length"),
        ({"start": [5, 5]}, "start"),
        ({"regions": {"goal": [0, 0, 1, 1], "shortcut": [0, 0, 1, 1]}}, "detour"),
        ({"units": "inch"}, "units"),
    ],
)
def test_bad_map_files_name_file_and_entry(tmp_path, changes, message):
    path = write_map(tmp_path, **changes)
    with pytest.raises(ValueError, match=message) as err:
        load_map(path)
    assert str(path) in str(err.value)


def test_missing_and_malformed_map_files(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        load_map(tmp_path / "nope.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_map(bad)
    data = json.loads(open(OFFICE.source).read())
    del data["walls"]
    bad.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="missing keys"):
        load_map(bad)
    with pytest.raises(TypeError, match="map must be a path"):
        load_map(42)


def test_misspelt_key_is_named_with_the_allowed_ones(tmp_path):
    data = json.loads(open(OFFICE.source).read())
    data["wals"] = data.pop("walls")
    bad = tmp_path / "typo.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"missing keys \['walls'\]; unknown keys \['wals'\] \(allowed: name, "):
        load_map(bad)
    region = write_map(tmp_path, regions={"gaol": [220, 0, 290, 305], "goal": [220, 0, 290, 305]})
    with pytest.raises(ValueError, match=r"unknown keys \['regions.gaol'\] \(allowed: regions.goal, "):
        load_map(region)


def test_goal_outside_the_bounds_says_so(tmp_path):
    path = write_map(tmp_path, regions={"goal": [300, 0, 400, 305]})
    with pytest.raises(ValueError, match=r"regions.goal \[300.0, 0.0, 400.0, 305.0\] lies outside the bounds \[0"):
        load_map(path)


def test_office_core_is_cached_per_file_version(tmp_path):
    path = write_map(tmp_path)
    first = office_core(path)
    assert office_core(str(path)) is first
    data = json.loads(path.read_text())
    data["start"] = [100, 60]
    path.write_text(json.dumps(data))
    stamp = path.stat().st_mtime_ns + 10**9  # visible even where the file system keeps coarse timestamps
    os.utime(path, ns=(stamp, stamp))
    edited = office_core(path)
    np.testing.assert_array_equal(edited.lattice.cells[edited.start_cell], [100, 60])
    with pytest.raises(ValueError, match="does not exist"):
        office_core(tmp_path / "nope.json")


def test_sensor_source_seam_for_databases():
    core = office_core()
    assert core.readings.shape == (len(core.lattice.cells), 32) and core.lattice.reachable.all()
    assert core.lattice.index(OFFICE.start) == core.start_cell and core.lattice.index((91.0, 60.0)) == -1
    cells = np.repeat(core.lattice.cells[:3], 4, axis=0)  # K = 4 recordings of 3 cells
    recorded = realistic_readings(OFFICE, cells, NoiseModel(), np.random.default_rng(0))
    assert recorded.shape == (12, 32) and recorded.dtype == np.float32
    assert recorded.min() >= 0.0 and recorded.max() <= 1.0
    assert not np.array_equal(recorded[0], recorded[1])
    np.testing.assert_allclose(
        realistic_readings(OFFICE, cells, NoiseModel(0, 0, 0, 0, 0), np.random.default_rng(0)),
        np.repeat(core.readings[:3], 4, axis=0),
    )
