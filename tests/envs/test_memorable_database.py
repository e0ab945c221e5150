"""MEMORABLE database: round trip, strict reader (every corruption named), CSV import."""

import json
from pathlib import Path

import numpy as np
import pytest

from twodrl_envs.memorable.database import (
    CSV_COLUMNS,
    SCHEMA_VERSION,
    import_csv,
    load_database,
    save_database,
)
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.geometry import default_map_path
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import HIGH_CM, LOW_CM, NoiseModel


@pytest.fixture(scope="module", params=["noise", "realistic"])
def db(request):
    """Both recorders: noisy ideal readings on each cell, and the stand-in robot driving by dead reckoning."""
    if request.param == "realistic":
        return record_database(2, model=RealisticModel(), seed=3)
    return record_database(2, noise=NoiseModel(), seed=3)


@pytest.fixture()
def saved(db, tmp_path):
    return save_database(db, tmp_path / "db.npz")


def _rewrite(src: Path, dst: Path, **changes) -> Path:
    with np.load(src, allow_pickle=False) as npz:
        arrays = {key: npz[key] for key in npz.files}
    for key, value in changes.items():
        if value is None:
            del arrays[key]
        else:
            arrays[key] = value
    np.savez(dst, **arrays)
    return dst


def test_round_trip_identical(db, saved):
    loaded = load_database(saved, office_core())
    for name in ("cells", "counts", "ranges_cm"):
        a, b = getattr(db, name), getattr(loaded, name)
        assert a.dtype == b.dtype and np.array_equal(a, b)
    assert loaded.metadata == db.metadata
    assert loaded.metadata["recording"]["samples_per_cell"] == 2
    assert loaded.metadata["sensors"]["sonar"]["count"] == 16


def test_record_covers_every_reachable_cell_k_times(db):
    core = office_core()
    if db.metadata["recording"]["sensor_model"].startswith("realistic"):
        # a run that bumps into a wall is driven again; after 20 tries a cell may keep fewer readings
        assert np.all(db.counts[core.lattice.reachable] >= 1) and np.all(db.counts <= 2)
        assert np.all(db.counts[~core.lattice.reachable] == 0)
    else:
        assert np.array_equal(db.counts, np.where(core.lattice.reachable, 2, 0))
    assert db.ranges_cm.shape == (int(db.counts.sum()), 32)


def test_realistic_recording_is_filed_by_drifting_odometry_and_repeats():
    one = record_database(1, model=RealisticModel(), seed=5)
    again = record_database(1, model=RealisticModel(), seed=5)
    np.testing.assert_array_equal(one.ranges_cm, again.ranges_cm)
    stats = one.metadata["recording"]
    assert stats["median_odometry_error_cm"] > 0.5 and stats["model"]["blank_cm"] == 42.0
    core = office_core()
    ideal = np.clip(core.ranges, LOW_CM, HIGH_CM)[np.repeat(np.arange(len(one.counts)), one.counts)]
    assert np.mean(np.abs(one.ranges_cm[:, :16] - ideal[:, :16]) > 50) > 0.2  # the gap, not noise


def test_recorder_arguments():
    with pytest.raises(ValueError, match="either model"):
        record_database(1, model=RealisticModel(), noise=NoiseModel())
    with pytest.raises(TypeError, match="model"):
        record_database(1, model="realistic")


def test_ideal_recording_is_the_exact_table():
    ideal = record_database(1)
    assert np.array_equal(ideal.readings(), office_core().readings)


def test_shipped_database_loads_and_matches_the_office():
    shipped = load_database(None, office_core())
    assert shipped.metadata["recording"]["samples_per_cell"] == 8
    assert shipped.metadata["recording"]["sensor_model"].startswith("realistic")


def test_missing_file(tmp_path):
    with pytest.raises(ValueError, match=r"nope\.npz does not exist"):
        load_database(tmp_path / "nope.npz")


def test_truncated_file(saved, tmp_path):
    bad = tmp_path / "truncated.npz"
    bad.write_bytes(saved.read_bytes()[: saved.stat().st_size // 2])
    with pytest.raises(ValueError, match=r"truncated\.npz is truncated or corrupted"):
        load_database(bad)


def test_corrupted_byte(saved, tmp_path):
    data = bytearray(saved.read_bytes())
    data[len(data) // 2] ^= 0xFF
    bad = tmp_path / "flipped.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"flipped\.npz is truncated or corrupted"):
        load_database(bad)


def test_not_a_database(tmp_path):
    bad = tmp_path / "text.npz"
    bad.write_text("hello")
    with pytest.raises(ValueError, match=r"text\.npz is not an npz archive"):
        load_database(bad)


def test_wrong_schema_version(saved, tmp_path):
    bad = _rewrite(saved, tmp_path / "v99.npz", schema_version=np.array(SCHEMA_VERSION + 98))
    with pytest.raises(ValueError, match=r"v99\.npz: schema version .*99.* not supported"):
        load_database(bad)


def test_missing_array(saved, tmp_path):
    bad = _rewrite(saved, tmp_path / "nocounts.npz", counts=None)
    with pytest.raises(ValueError, match=r"nocounts\.npz: missing arrays \['counts'\]"):
        load_database(bad)


def test_non_finite_readings(saved, db, tmp_path):
    ranges = db.ranges_cm.copy()
    ranges[5, 20] = np.nan
    bad = _rewrite(saved, tmp_path / "nan.npz", ranges_cm=ranges)
    with pytest.raises(ValueError, match=r"nan\.npz: 1 non-finite readings.*ir_4"):
        load_database(bad)


def test_out_of_range_readings(saved, db, tmp_path):
    ranges = db.ranges_cm.copy()
    ranges[0, 0] = 900.0
    bad = _rewrite(saved, tmp_path / "far.npz", ranges_cm=ranges)
    with pytest.raises(ValueError, match=r"far\.npz: 1 readings outside the sensors' ranges, first sonar_0 = 900"):
        load_database(bad)


def test_counts_rows_mismatch(saved, db, tmp_path):
    bad = _rewrite(saved, tmp_path / "short.npz", ranges_cm=db.ranges_cm[:-1])
    with pytest.raises(ValueError, match=r"short\.npz: 'counts' sum to"):
        load_database(bad)


def _other_map(tmp_path: Path, move_block_cm: float = 0.0, reformat: bool = False) -> Path:
    data = json.loads(default_map_path().read_text())
    data["obstacles"][0] = [[x + move_block_cm, y] for x, y in data["obstacles"][0]]
    path = tmp_path / "office2.json"
    path.write_text(json.dumps(data, indent=7 if reformat else None))
    return path


def test_map_mismatch(saved, tmp_path):
    core = office_core(_other_map(tmp_path, move_block_cm=10.0))
    with pytest.raises(ValueError, match=r"db\.npz: recorded in map 'nomad-office-dilemma' .*office2\.json has sha256"):
        load_database(saved, core)


def test_reformatted_map_still_matches(saved, tmp_path):
    load_database(saved, office_core(_other_map(tmp_path, reformat=True)))


def test_cell_list_mismatch(saved, db, tmp_path):
    cells = db.cells.copy()
    cells[0, 0] += 10.0
    bad = _rewrite(saved, tmp_path / "cells.npz", cells=cells)
    with pytest.raises(ValueError, match=r"cells\.npz: its cell list does not match the lattice"):
        load_database(bad, office_core())


def _write_csv(path: Path, rows: list[list[float]], header=CSV_COLUMNS) -> Path:
    lines = [",".join(header)] + [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _row(x, y, sonar=100.0, ir=40.0):
    return [x, y] + [sonar] * 16 + [ir] * 16


def test_csv_import_tiny_log(tmp_path):
    core = office_core()
    log = _write_csv(
        tmp_path / "log.csv",
        [_row(60, 85, 100), _row(61.5, 84, 120.5), _row(70, 85, 200, 12.5), _row(60, 95)],
    )
    db = import_csv(log, require_all_cells=False)
    start, east, north = core.start_cell, core.lattice.index((70, 85)), core.lattice.index((60, 95))
    assert db.counts.sum() == 4 and db.counts[start] == 2 and db.counts[east] == 1 and db.counts[north] == 1
    assert np.array_equal(db.cell_readings(start)[:, 0], [100.0, 120.5])
    assert np.array_equal(db.cell_readings(east)[0], [200.0] * 16 + [12.5] * 16)
    loaded = load_database(save_database(db, tmp_path / "log.npz"), core)
    assert np.array_equal(loaded.ranges_cm, db.ranges_cm)
    assert loaded.metadata["recording"]["source"] == "csv"


def test_csv_requires_all_reachable_cells_by_default(tmp_path):
    log = _write_csv(tmp_path / "few.csv", [_row(60, 85)])
    with pytest.raises(ValueError, match=r"few\.csv: 339 reachable cells have no readings"):
        import_csv(log)


@pytest.mark.parametrize(
    ("row", "message"),
    [
        (_row(500, 85), r"line 2: position \(500.0, 85.0\) is off the map"),
        (_row(65, 85), r"line 2: position \(65.0, 85.0\) is off the 10 cm lattice"),
        (_row(170, 115), r"line 2: position \(170.0, 115.0\) .* is not free space"),
        (_row(60, 85, 700), r"line 2: sonar_0 = 700.0 is outside"),
        (_row(60, 85, float("nan")), r"line 2: non-finite value"),
    ],
)
def test_csv_errors(tmp_path, row, message):
    log = _write_csv(tmp_path / "bad.csv", [row])
    with pytest.raises(ValueError, match=r"bad\.csv " + message):
        import_csv(log, require_all_cells=False, tolerance_cm=2.0)


def test_csv_missing_column(tmp_path):
    log = _write_csv(tmp_path / "cols.csv", [_row(90, 60)[:-1]], header=CSV_COLUMNS[:-1])
    with pytest.raises(ValueError, match=r"cols\.csv: missing columns \['ir_15'\]"):
        import_csv(log)
