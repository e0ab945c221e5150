"""``NomadOfficeMemorable-v0``: the office task replayed from a recorded sensor database.

Each step's observation is one of the readings recorded at the robot's new cell, picked with a
counter-based draw from the env's seeded key (so the batched env reproduces single envs), and a
move collides where the map's swept-disc test says so or where it would enter a cell without
recordings (the recorded free space). Rewards, ``info`` keys, time limit and the observation
layout (``observation="cell"`` included) are those of ``NomadOffice-v0``.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np

from twodrl_envs.memorable.database import SensorDatabase, load_database
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_envs.nomad.core import OfficeCore, Robot, counter_word
from twodrl_envs.nomad.episode import sensor_noise_model
from twodrl_envs.nomad.office import NomadOfficeEnv
from twodrl_envs.nomad.sensors import NoiseModel

RECORDED = "recorded:"
"""Prefix of ``database="recorded:K:SEED"``: the stand-in robot's recording of the env's map, made on demand."""
READINGS = ("all", "fit", "held_out")
"""What a replay robot replays of each cell's recordings (:func:`split_readings`)."""
NOISE_SALT = np.uint64(0x5DEECE66D)
"""XORed into a replay robot's episode key for its ``sensor_noise`` draws, so they are apart from the reading picks."""
HOLD_OUT = 4
"""One in this many of a cell's recordings (rounded up, the last ones recorded) is held out (:func:`split_readings`)."""


def split_readings(counts: np.ndarray, readings: str) -> np.ndarray:
    """Which recordings ``(sum(counts),)`` bool a replay robot with option ``readings`` replays, of a database whose
    cells hold ``counts`` recordings each, grouped by cell.

    ``"all"``: every one. ``"held_out"``: of a cell with ``n >= 2`` recordings, its last ``ceil(n / HOLD_OUT)``
    (the recorder's last tours, a survey's last draws at the cell: other drifts and pings than the rest);
    ``"fit"``: the others. A cell with one recording keeps it in both, as it cannot be split. Training on
    ``"fit"`` and checking on ``"held_out"`` tests the policy on readings it was not trained on, as the robot's own
    will be.

    :raises ValueError: if ``readings`` is not one of :data:`READINGS`
    """
    if readings not in READINGS:
        raise ValueError(f"readings must be one of {READINGS}, got {readings!r}")
    counts = np.asarray(counts, dtype=np.int64)
    if readings == "all":
        return np.ones(int(counts.sum()), dtype=bool)
    cell = np.repeat(np.arange(len(counts)), counts)
    rank = np.arange(len(cell)) - np.repeat(np.cumsum(counts) - counts, counts)
    held = np.where(counts >= 2, -(-counts // HOLD_OUT), 0)[cell]
    last = rank >= counts[cell] - held
    return last | (held == 0) if readings == "held_out" else ~last


def recorded(core: OfficeCore, database: str) -> SensorDatabase:
    """The database ``"recorded:K:SEED"`` names: ``K`` readings per cell recorded in ``core``'s map by the stand-in
    robot of ``NomadOfficeReal-v0`` driving by dead reckoning, with ``seed``
    (:func:`~twodrl_envs.memorable.recording.record_database`, as ``sb3-twodrl-record-database --k K --seed SEED``
    records it); made once per process and map.

    :raises ValueError: naming ``database``, if K or SEED is not an int (K >= 1, SEED >= 0)
    """
    k, _, seed = database.removeprefix(RECORDED).partition(":")
    if not (k.isdigit() and seed.isdigit() and int(k) >= 1):
        raise ValueError(f"database must be 'recorded:K:SEED' with ints K >= 1 and SEED >= 0, got {database!r}")
    db = _recorded(core.office.source, int(k), int(seed))
    db.check_map(core)  # a map file edited since this process recorded it
    return db


@functools.lru_cache(maxsize=4)
def _recorded(source: str, k: int, seed: int) -> SensorDatabase:
    from twodrl_envs.memorable.recording import record_database
    from twodrl_envs.nomad.realistic import RealisticModel

    return record_database(k, map=source, model=RealisticModel(), seed=seed)


class ReplayRobot(Robot):
    """A robot that replays a sensor database: on the lattice, moving only between recorded cells.

    A move collides where the map's swept-disc test says so or where it would enter a cell without
    recordings (the recorded free space); a reading is reading ``hash(key, step) mod count`` of the
    cell's recordings; of all of them, or of the ``readings`` :func:`split_readings` picks.
    """

    def __init__(
        self,
        core: OfficeCore,
        database: str | Path | SensorDatabase | None,
        readings: str = "all",
        noise: NoiseModel | None = None,
    ) -> None:
        super().__init__(core)
        if isinstance(database, SensorDatabase):
            database.check_map(core)
            db = database
        elif isinstance(database, str) and database.startswith(RECORDED):
            db = recorded(core, database)
        else:
            db = load_database(database, core)
        self.database = db
        replayed = split_readings(db.counts, readings)
        cell = np.repeat(np.arange(len(db.counts)), db.counts)
        counts = np.bincount(cell[replayed], minlength=len(db.counts))
        kept = dataclasses.replace(db, counts=counts, ranges_cm=db.ranges_cm[replayed])  # the replayed recordings
        self.ranges_cm, self.readings, self.offsets = kept.ranges_cm, kept.readings(), kept.offsets
        self.counts = counts.astype(np.uint64)
        self.noise = noise
        moves = core.lattice.moves.copy()
        moves[(moves >= 0) & (db.counts[np.maximum(moves, 0)] == 0)] = -1
        self.moves = moves
        self._offsets, self._counts = self.offsets.tolist(), counts.tolist()

    def cell_readings(self, cells: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Recorded readings ``(n, 32)`` of ``cells``: reading ``hash(key, step) mod count`` of each."""
        word = sensors.counter_hash(keys, steps)[:, 0]
        rows = self.offsets[cells] + (word % self.counts[cells]).astype(np.int64)
        if self.noise is None:
            return self.readings[rows]
        return sensors.normalise(self.noise.apply(self.ranges_cm[rows], keys ^ NOISE_SALT, steps))

    def cell_reading(self, cell: int, key: int, step: int) -> np.ndarray:
        """:meth:`cell_readings` of one robot, in Python integers (a single env's step is mostly call overhead)."""
        if self.noise is not None:
            return super().cell_reading(cell, key, step)
        return self.readings[self._offsets[cell] + counter_word(key, step) % self._counts[cell]]

    def check_start(self, xy: np.ndarray, cell: int) -> None:
        if cell < 0 or self.database.counts[cell] == 0:
            raise ValueError(f"options['position'] {tuple(float(v) for v in xy)} is not a recorded lattice cell")


def replay_robot(
    core: OfficeCore,
    generators: object,
    *,
    database: str | Path | SensorDatabase | None = None,
    readings: str = "all",
    sensor_noise: bool | NoiseModel | None = None,
) -> ReplayRobot:
    """The replay robot of ``NomadOfficeMemorable-v0`` with its options ``database``, ``readings`` and
    ``sensor_noise`` (:func:`~twodrl_envs.nomad.episode.sensor_noise_model`) (:class:`ReplayRobot`); it draws from
    no generator."""
    return ReplayRobot(core, database, readings, sensor_noise_model(sensor_noise))


class NomadOfficeMemorableEnv(NomadOfficeEnv):
    """The Nomad office task trained from recorded readings (paper section 3.1, MEMORABLE).

    ``database`` is a file written by :func:`twodrl_envs.memorable.database.save_database`, a loaded
    :class:`~twodrl_envs.memorable.database.SensorDatabase`, ``None`` for the shipped one (realistic
    sensor model, K = 8), or ``"recorded:K:SEED"`` to record one in ``map`` now (:func:`recorded`); it must
    have been recorded in ``map``. ``readings`` (one of :data:`READINGS`, default ``"all"``) replays every
    recording, or a split of each cell's (:func:`split_readings`): ``"fit"`` to train on, ``"held_out"`` to check
    on. ``sensor_noise`` (as ``NomadOffice-v0``'s: ``True`` the default
    :class:`~twodrl_envs.nomad.sensors.NoiseModel`) adds per-step noise to the replayed readings. Motion is on the
    lattice, so ``options["position"]`` must be a recorded cell. The robot is a :class:`ReplayRobot` (``env.robot``).
    """

    robot_factory = replay_robot


class BatchedNomadOfficeMemorable(BatchedNomadOffice):
    """``num_envs`` replay robots in one numpy call; sub-env ``i`` equals a seeded single env."""

    single_env = NomadOfficeMemorableEnv
