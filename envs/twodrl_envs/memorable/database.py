"""MEMORABLE sensor databases: recorded readings per lattice cell (paper section 3.1).

A database holds, for cells of an office's 10 cm lattice, the readings of the 16 sonar and
16 infrared sensors a robot recorded there (any number per cell, usually K), in centimetres as
the sensors report them (saturated to their valid ranges), plus the map it was recorded in and
how it was recorded. The file is a numpy ``.npz`` archive (schema in ``docs/memorable.md``);
:func:`load_database` is strict: every problem is a ``ValueError`` naming the file.
"""

from __future__ import annotations

import csv
import datetime as _dt
import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import OfficeCore, office_core
from twodrl_envs.nomad.geometry import ROBOT_RADIUS_CM, SHIPPED_MAPS, STEP_CM, OfficeMap
from twodrl_envs.nomad.maps import map_data, map_source
from twodrl_envs.nomad.sensors import HIGH_CM, LOW_CM

SCHEMA_VERSION = 1
FORMAT_NAME = "sb3-twodrl-memorable"
_ARRAYS = ("format", "schema_version", "metadata", "cells", "counts", "ranges_cm")
SENSOR_COLUMNS = tuple(f"sonar_{i}" for i in range(sensors.N_SONAR)) + tuple(f"ir_{i}" for i in range(sensors.N_IR))
CSV_COLUMNS = ("x_cm", "y_cm", *SENSOR_COLUMNS)


def _xy(xy: Any) -> str:
    return f"({float(xy[0])}, {float(xy[1])})"


def default_database_path(map: str | Path | None = None) -> Path:
    """The database shipped for a shipped map (realistic sensor model, K = 8); others get the office's.

    ``map`` as :func:`twodrl_envs.nomad.maps.map_source` takes it: ``None``/``"office"`` is the default
    office (``office_k8.npz``), a name in :data:`~twodrl_envs.nomad.geometry.SHIPPED_MAPS` its ``<name>_k8.npz``.
    """
    source = map_source(map)
    name = next((name for name in SHIPPED_MAPS if source == map_source(name)), "office")
    return Path(__file__).with_name("data") / f"{name}_k8.npz"


def _floats(value: Any) -> Any:
    """JSON data with every number as a float, so ``140`` and ``140.0`` hash alike."""
    if isinstance(value, dict):
        return {k: _floats(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_floats(v) for v in value]
    if isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def map_fingerprint(office: OfficeMap) -> tuple[str, str]:
    """Canonical JSON text of a map (file or generated) and its SHA-256 (whitespace, key order, 1 vs 1.0 do not
    matter)."""
    data = _floats(map_data(office.source))
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return text, hashlib.sha256(text.encode()).hexdigest()


def sensor_spec() -> dict[str, Any]:
    """The sensor specification stored with every database (units cm, bearings in degrees)."""
    return {
        "units": "cm",
        "sonar": {"count": sensors.N_SONAR, "min_cm": sensors.SONAR_MIN_CM, "max_cm": sensors.SONAR_MAX_CM},
        "ir": {"count": sensors.N_IR, "min_cm": 0.0, "max_cm": sensors.IR_MAX_CM},
        "bearing_deg": "sensor i of each ring at i * 22.5 degrees counter-clockwise from north, heading fixed north",
        "range_from": "body surface",
        "column_order": list(SENSOR_COLUMNS),
    }


@dataclass(frozen=True)
class SensorDatabase:
    """Recorded readings of one office.

    ``cells`` ``(n_cells, 2)`` are the office lattice's free cell centres (cm, lattice order);
    ``counts`` ``(n_cells,)`` the number of readings recorded at each cell (0: not recorded, so
    outside the recorded free space); ``ranges_cm`` ``(sum(counts), 32)`` the readings, grouped
    by cell in cell order (16 sonar then 16 IR, saturated cm). ``metadata`` is a JSON-able dict.
    """

    cells: np.ndarray
    counts: np.ndarray
    ranges_cm: np.ndarray
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def offsets(self) -> np.ndarray:
        """Index of each cell's first reading in ``ranges_cm`` ``(n_cells,)``."""
        return np.concatenate([[0], np.cumsum(self.counts)[:-1]]).astype(np.int64)

    def readings(self) -> np.ndarray:
        """The recordings as normalised observations ``(sum(counts), 32)`` float32."""
        return sensors.normalise(self.ranges_cm)

    def cell_readings(self, cell: int) -> np.ndarray:
        """Recorded ranges ``(counts[cell], 32)`` of one cell."""
        start = int(self.offsets[cell])
        return self.ranges_cm[start : start + int(self.counts[cell])]

    def check_map(self, core: OfficeCore, source: str = "database") -> None:
        """Raise ``ValueError`` unless the database was recorded in ``core``'s map and covers its start."""
        _, digest = map_fingerprint(core.office)
        if self.metadata.get("map_sha256") != digest:
            raise ValueError(
                f"{source}: recorded in map {self.metadata.get('map_name')!r} (sha256 "
                f"{str(self.metadata.get('map_sha256'))[:12]}...), but the environment's map {core.office.source} "
                f"has sha256 {digest[:12]}...; record a database for this map"
            )
        if self.cells.shape != core.lattice.cells.shape or not np.array_equal(self.cells, core.lattice.cells):
            raise ValueError(f"{source}: its cell list does not match the lattice of map {core.office.source}")
        if self.counts[core.start_cell] == 0:
            raise ValueError(f"{source}: no readings recorded at the start cell {_xy(core.office.start)}")


def database_metadata(core: OfficeCore, recording: dict[str, Any]) -> dict[str, Any]:
    text, digest = map_fingerprint(core.office)
    return {
        "map_name": core.office.name,
        "map_sha256": digest,
        "map_json": text,
        "robot_radius_cm": ROBOT_RADIUS_CM,
        "lattice_step_cm": STEP_CM,
        "sensors": sensor_spec(),
        "recording": recording,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }


def save_database(db: SensorDatabase, path: str | Path) -> Path:
    """Write ``db`` as a compressed ``.npz`` (schema :data:`SCHEMA_VERSION`); returns the path."""
    path = Path(path)
    if path.suffix != ".npz":
        raise ValueError(f"database file {path} must end in .npz")
    _validate(db.cells, db.counts, db.ranges_cm, str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path,
        format=np.array(FORMAT_NAME),
        schema_version=np.array(SCHEMA_VERSION, dtype=np.int64),
        metadata=np.array(json.dumps(db.metadata, sort_keys=True)),
        cells=np.ascontiguousarray(db.cells, dtype=np.float64),
        counts=np.ascontiguousarray(db.counts, dtype=np.int64),
        ranges_cm=np.ascontiguousarray(db.ranges_cm, dtype=np.float64),
    )
    return path


def _validate(cells: np.ndarray, counts: np.ndarray, ranges: np.ndarray, name: str) -> None:
    where = f"database file {name}"
    if cells.ndim != 2 or cells.shape[1] != 2 or cells.dtype != np.float64:
        raise ValueError(f"{where}: 'cells' must be float64 (n_cells, 2), got {cells.dtype} {cells.shape}")
    if counts.shape != (len(cells),) or counts.dtype != np.int64:
        raise ValueError(f"{where}: 'counts' must be int64 ({len(cells)},), got {counts.dtype} {counts.shape}")
    if np.any(counts < 0):
        raise ValueError(f"{where}: 'counts' has negative entries")
    if ranges.ndim != 2 or ranges.shape[1] != sensors.N_READINGS or ranges.dtype != np.float64:
        raise ValueError(
            f"{where}: 'ranges_cm' must be float64 (n, {sensors.N_READINGS}), got {ranges.dtype} {ranges.shape}"
        )
    if len(ranges) != int(counts.sum()):
        raise ValueError(f"{where}: 'counts' sum to {int(counts.sum())} but 'ranges_cm' has {len(ranges)} rows")
    if not np.all(np.isfinite(cells)):
        raise ValueError(f"{where}: 'cells' holds non-finite positions")
    bad = ~np.isfinite(ranges)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        cell = int(np.searchsorted(np.cumsum(counts), row, side="right"))
        raise ValueError(
            f"{where}: {int(bad.sum())} non-finite readings, first {ranges[row, col]} "
            f"({SENSOR_COLUMNS[col]}) at cell {_xy(cells[cell])}"
        )
    out = (ranges < LOW_CM) | (ranges > HIGH_CM)
    if out.any():
        row, col = np.argwhere(out)[0]
        raise ValueError(
            f"{where}: {int(out.sum())} readings outside the sensors' ranges, first "
            f"{SENSOR_COLUMNS[col]} = {ranges[row, col]} (valid {LOW_CM[col]}-{HIGH_CM[col]} cm)"
        )


def load_database(path: str | Path | None = None, core: OfficeCore | None = None) -> SensorDatabase:
    """Read a database file strictly; ``None`` is the one shipped for ``core``'s map. With ``core``, also check the map.

    Raises ``ValueError`` naming the file for a missing, truncated or corrupted file, a wrong
    format or schema version, missing or malformed arrays, non-finite or out-of-range readings,
    and (with ``core``) a map or lattice that differs from the environment's.
    """
    defaulted = path is None
    path = default_database_path(None if core is None else core.office.source) if path is None else Path(path)
    name = str(path)
    if not path.is_file():
        where = "" if core is None else f" --map {core.office.source}"
        raise ValueError(
            f"database file {path.resolve()} does not exist: record one with "
            f"`sb3-twodrl-record-database{where} --out {path}`"
        )
    with path.open("rb") as fh:
        magic = fh.read(4)
    if magic != b"PK\x03\x04":
        raise ValueError(f"database file {name} is not an npz archive (truncated or corrupted): starts with {magic!r}")
    arrays: dict[str, np.ndarray] = {}
    try:
        with np.load(path, allow_pickle=False) as npz:
            missing = [key for key in _ARRAYS if key not in npz.files]
            if missing:
                raise ValueError(f"database file {name}: missing arrays {missing} (found {sorted(npz.files)})")
            for key in _ARRAYS:
                arrays[key] = npz[key]
    except ValueError as err:
        if str(err).startswith(f"database file {name}"):
            raise
        raise ValueError(f"database file {name} is corrupted or not a database: {err}") from err
    except Exception as err:  # corrupted bytes fail deep in zipfile, zlib or numpy's header parser, in many ways
        raise ValueError(f"database file {name} is truncated or corrupted: {type(err).__name__}: {err}") from err
    if arrays["format"].shape != () or str(arrays["format"]) != FORMAT_NAME:
        raise ValueError(f"database file {name}: format is {arrays['format']!r}, expected {FORMAT_NAME!r}")
    version = arrays["schema_version"]
    if version.shape != () or version.dtype.kind not in "iu" or int(version) != SCHEMA_VERSION:
        raise ValueError(
            f"database file {name}: schema version {version!r} is not supported (this reader reads {SCHEMA_VERSION})"
        )
    try:
        metadata = json.loads(str(arrays["metadata"]))
    except json.JSONDecodeError as err:
        raise ValueError(f"database file {name}: metadata is not valid JSON: {err}") from err
    if not isinstance(metadata, dict) or "map_sha256" not in metadata:
        raise ValueError(f"database file {name}: metadata must be an object with 'map_sha256'")
    _validate(arrays["cells"], arrays["counts"], arrays["ranges_cm"], name)
    db = SensorDatabase(arrays["cells"], arrays["counts"], arrays["ranges_cm"], metadata)
    if core is not None:
        try:
            db.check_map(core, f"database file {name}")
        except ValueError as err:
            if not defaulted:
                raise
            raise ValueError(
                f"{err}. No database ships for this map: record one with `sb3-twodrl-record-database --map "
                f"{core.office.source} --out DB.npz` and pass database='DB.npz'"
            ) from err
    return db


def import_csv(
    path: str | Path,
    *,
    map: str | Path | None = None,
    require_all_cells: bool = True,
    tolerance_cm: float = 5.0,
    per_cell: int | None = None,
) -> SensorDatabase:
    """Build a database from a CSV log with columns ``x_cm, y_cm, sonar_0..sonar_15, ir_0..ir_15``.

    One row per reading; each position is snapped to the nearest lattice cell (within
    ``tolerance_cm`` per axis). A position off the map, in a wall, or farther than the tolerance
    from a free cell, a missing column, a non-numeric, non-finite or out-of-range value are
    ``ValueError`` naming the file and line. With ``require_all_cells`` every cell reachable from
    the start must have at least one reading (otherwise the missing cells are listed); ``per_cell`` keeps each
    cell's first readings only (:func:`import_readings`).
    """
    path = Path(path)
    name = str(path)
    if not path.is_file():
        raise ValueError(f"CSV log {name} does not exist")
    rows, labels = [], []
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        header = [h.strip() for h in (reader.fieldnames or [])]
        missing = [c for c in CSV_COLUMNS if c not in header]
        if missing:
            raise ValueError(f"CSV log {name}: missing columns {missing}")
        reader.fieldnames = header
        for line, row in enumerate(reader, start=2):
            try:
                values = np.array([float(row[c]) for c in CSV_COLUMNS])
            except (TypeError, ValueError) as err:
                raise ValueError(f"CSV log {name} line {line}: non-numeric or missing value ({err})") from err
            if not np.all(np.isfinite(values)):
                raise ValueError(f"CSV log {name} line {line}: non-finite value")
            rows.append(values)
            labels.append(f"CSV log {name} line {line}")
    recording = {
        "source": "csv",
        "file": path.name,
        "how": "imported from a CSV log of robot readings, positions snapped to the 10 cm lattice",
    }
    table = np.array(rows).reshape(-1, len(CSV_COLUMNS))
    return import_readings(
        table[:, :2],
        table[:, 2:],
        map=map,
        source=f"CSV log {name}",
        labels=labels,
        recording=recording,
        require_all_cells=require_all_cells,
        tolerance_cm=tolerance_cm,
        per_cell=per_cell,
    )


def import_readings(
    positions_cm: np.ndarray,
    ranges_cm: np.ndarray,
    *,
    map: str | Path | None = None,
    source: str = "log",
    labels: list[str] | None = None,
    recording: dict[str, Any] | None = None,
    require_all_cells: bool = True,
    tolerance_cm: float = 5.0,
    per_cell: int | None = None,
) -> SensorDatabase:
    """Build a database from a robot's readings ``(n, 32)`` (cm, sensor order of :data:`SENSOR_COLUMNS`) and the
    positions ``(n, 2)`` (cm, the map's frame) they were taken at: what every import (:func:`import_csv`, a ROS 2
    bag) reduces its log to.

    Each position is snapped to the nearest lattice cell (within ``tolerance_cm`` per axis); ``per_cell`` keeps a
    cell's first readings only. ``ValueError`` names ``source`` and the reading (``labels[i]``, default
    ``"{source} reading {i}"``) for an out-of-range value, a position off the map, off the lattice or in a wall;
    with ``require_all_cells``, for reachable cells without readings (listed). ``recording`` goes into the
    metadata, with the counts.
    """
    positions_cm = np.asarray(positions_cm, dtype=np.float64)
    ranges_cm = np.asarray(ranges_cm, dtype=np.float64)
    if positions_cm.ndim != 2 or positions_cm.shape[1] != 2 or ranges_cm.shape != (len(positions_cm), 32):
        raise ValueError(
            f"positions_cm must be (n, 2) and ranges_cm (n, 32), got {positions_cm.shape} and {ranges_cm.shape}"
        )
    if per_cell is not None and (isinstance(per_cell, bool) or not isinstance(per_cell, int) or per_cell < 1):
        raise ValueError(f"per_cell must be a positive int or None, got {per_cell!r}")
    if labels is None:
        labels = [f"{source} reading {i}" for i in range(len(positions_cm))]
    core = office_core(map)
    lat = core.lattice
    per: dict[int, list[np.ndarray]] = {}
    for label, xy, reading in zip(labels, positions_cm, ranges_cm, strict=True):
        if not np.all(np.isfinite(xy)) or not np.all(np.isfinite(reading)):
            raise ValueError(f"{label}: non-finite value")
        out = (reading < LOW_CM) | (reading > HIGH_CM)
        if out.any():
            col = int(np.flatnonzero(out)[0])
            raise ValueError(
                f"{label}: {SENSOR_COLUMNS[col]} = {reading[col]} is outside the "
                f"sensor's range {LOW_CM[col]}-{HIGH_CM[col]} cm"
            )
        if not core.office.inside_bounds(xy):
            raise ValueError(f"{label}: position {_xy(xy)} is off the map {core.office.bounds}")
        grid = np.round((xy - lat.origin) / STEP_CM)
        snapped = lat.origin + grid * STEP_CM
        if np.any(np.abs(xy - snapped) > tolerance_cm):
            raise ValueError(f"{label}: position {_xy(xy)} is off the 10 cm lattice")
        cell = lat.index(snapped)
        if cell < 0:
            raise ValueError(
                f"{label}: position {_xy(xy)} (cell {_xy(snapped)}) is not free "
                f"space for a {2 * ROBOT_RADIUS_CM:.0f} cm robot on map {core.office.source}"
            )
        kept = per.setdefault(cell, [])
        if per_cell is None or len(kept) < per_cell:
            kept.append(reading)
    if not per:
        raise ValueError(f"{source}: no readings")
    counts = np.zeros(len(lat.cells), dtype=np.int64)
    for cell, rows in per.items():
        counts[cell] = len(rows)
    if require_all_cells:
        missing_cells = np.flatnonzero(lat.reachable & (counts == 0))
        if len(missing_cells):
            shown = ", ".join(_xy(lat.cells[c]) for c in missing_cells[:5])
            raise ValueError(
                f"{source}: {len(missing_cells)} reachable cells have no readings (e.g. {shown}); "
                "record them or pass require_all_cells=False (unrecorded cells then count as obstacles)"
            )
    ranges = np.concatenate([np.array(per[c]) for c in sorted(per)], axis=0)
    recording = {**(recording or {}), "rows": int(counts.sum()), "cells_recorded": int((counts > 0).sum())}
    return SensorDatabase(lat.cells.copy(), counts, ranges, database_metadata(core, recording))
