"""``NomadOfficeMemorable-v0``: the office task replayed from a recorded sensor database.

Each step's observation is one of the readings recorded at the robot's new cell, picked with a
counter-based draw from the env's seeded key (so the batched env reproduces single envs), and a
move collides where the map's swept-disc test says so or where it would enter a cell without
recordings (the recorded free space). Rewards, ``info`` keys, time limit and the observation
layout (``observation="cell"`` included) are those of ``NomadOffice-v0``.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from twodrl_envs.memorable.database import SensorDatabase, load_database
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_envs.nomad.core import OfficeCore, Robot, counter_word
from twodrl_envs.nomad.office import NomadOfficeEnv

RECORDED = "recorded:"
"""Prefix of ``database="recorded:K:SEED"``: the stand-in robot's recording of the env's map, made on demand."""


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
    cell's recordings.
    """

    def __init__(self, core: OfficeCore, database: str | Path | SensorDatabase | None) -> None:
        super().__init__(core)
        if isinstance(database, SensorDatabase):
            database.check_map(core)
            db = database
        elif isinstance(database, str) and database.startswith(RECORDED):
            db = recorded(core, database)
        else:
            db = load_database(database, core)
        self.database = db
        self.readings = db.readings()
        self.counts = db.counts.astype(np.uint64)
        self.offsets = db.offsets
        moves = core.lattice.moves.copy()
        moves[(moves >= 0) & (db.counts[np.maximum(moves, 0)] == 0)] = -1
        self.moves = moves
        self._offsets, self._counts = self.offsets.tolist(), db.counts.tolist()

    def cell_readings(self, cells: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Recorded readings ``(n, 32)`` of ``cells``: reading ``hash(key, step) mod count`` of each."""
        word = sensors.counter_hash(keys, steps)[:, 0]
        return self.readings[self.offsets[cells] + (word % self.counts[cells]).astype(np.int64)]

    def cell_reading(self, cell: int, key: int, step: int) -> np.ndarray:
        """:meth:`cell_readings` of one robot, in Python integers (a single env's step is mostly call overhead)."""
        return self.readings[self._offsets[cell] + counter_word(key, step) % self._counts[cell]]

    def check_start(self, xy: np.ndarray, cell: int) -> None:
        if cell < 0 or self.database.counts[cell] == 0:
            raise ValueError(f"options['position'] {tuple(float(v) for v in xy)} is not a recorded lattice cell")


def replay_robot(
    core: OfficeCore, generators: object, *, database: str | Path | SensorDatabase | None = None
) -> ReplayRobot:
    """The replay robot of ``NomadOfficeMemorable-v0`` with its option ``database`` (:class:`ReplayRobot`); it
    draws from no generator."""
    return ReplayRobot(core, database)


class NomadOfficeMemorableEnv(NomadOfficeEnv):
    """The Nomad office task trained from recorded readings (paper section 3.1, MEMORABLE).

    ``database`` is a file written by :func:`twodrl_envs.memorable.database.save_database`, a loaded
    :class:`~twodrl_envs.memorable.database.SensorDatabase`, ``None`` for the shipped one (realistic
    sensor model, K = 8), or ``"recorded:K:SEED"`` to record one in ``map`` now (:func:`recorded`); it must
    have been recorded in ``map``. Motion is on the lattice, so
    ``options["position"]`` must be a recorded cell. The robot is a :class:`ReplayRobot` (``env.robot``).
    """

    robot_factory = replay_robot


class BatchedNomadOfficeMemorable(BatchedNomadOffice):
    """``num_envs`` replay robots in one numpy call; sub-env ``i`` equals a seeded single env."""

    single_env = NomadOfficeMemorableEnv
