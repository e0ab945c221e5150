"""``NomadOfficeMemorable-v0``: the office task replayed from a recorded sensor database.

Each step's observation is one of the readings recorded at the robot's new cell, picked with a
counter-based draw from the env's seeded key (so the batched env reproduces single envs), and a
move collides where the map's swept-disc test says so or where it would enter a cell without
recordings (the recorded free space). Rewards, ``info`` keys, time limit and the observation
layout (``observation="cell"`` included) are those of ``NomadOffice-v0``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.memorable.database import SensorDatabase, load_database
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.batched import BatchedNomadOffice, SB3VecEnvAdapter, make_sb3_vec_env
from twodrl_envs.nomad.office import NomadOfficeEnv, OfficeCore, counter_word


class _Replay:
    """Per-map replay tables shared by the single and the batched env."""

    def __init__(self, core: OfficeCore, database: str | Path | SensorDatabase | None) -> None:
        if isinstance(database, SensorDatabase):
            database.check_map(core)
            db = database
        else:
            db = load_database(database, core)
        self.database = db
        self.readings = db.readings()
        self.counts = db.counts.astype(np.uint64)
        self.offsets = db.offsets
        moves = core.lattice.moves.copy()
        moves[(moves >= 0) & (db.counts[np.maximum(moves, 0)] == 0)] = -1
        self.moves = moves

    def draw(self, cells: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Recorded readings ``(n, 32)`` of ``cells``: reading ``hash(key, step) mod count`` of each."""
        word = sensors.counter_hash(keys, steps)[:, 0]
        return self.readings[self.offsets[cells] + (word % self.counts[cells]).astype(np.int64)]


class NomadOfficeMemorableEnv(NomadOfficeEnv):
    """The Nomad office task trained from recorded readings (paper section 3.1, MEMORABLE).

    ``database`` is a file written by :func:`twodrl_envs.memorable.database.save_database`, a loaded
    :class:`~twodrl_envs.memorable.database.SensorDatabase`, or ``None`` for the shipped one (realistic
    sensor model, K = 8); it must have been recorded in ``map``. Motion is on the lattice, so
    ``options["position"]`` must be a recorded cell.
    """

    def __init__(
        self,
        map: str | Path | None = None,
        *,
        database: str | Path | SensorDatabase | None = None,
        observe_odometry: bool = True,
        render_mode: str | None = None,
        observation: str = "sensors",
    ) -> None:
        super().__init__(map, observe_odometry=observe_odometry, render_mode=render_mode, observation=observation)
        self.replay = _Replay(self.core, database)
        self._moves = self.replay.moves
        self._offsets, self._counts = self.replay.offsets.tolist(), self.replay.database.counts.tolist()

    def _lattice_readings(self, cell: int) -> np.ndarray:
        """:meth:`_Replay.draw` of one cell, in Python integers (a single env's step is mostly call overhead)."""
        word = counter_word(int(self._key[0]), int(self._step[0]))
        return self.replay.readings[self._offsets[cell] + word % self._counts[cell]]

    def _check_position(self, position: object) -> np.ndarray:
        xy = super()._check_position(position)
        cell = self.core.lattice.index(xy)
        if cell < 0 or self.replay.database.counts[cell] == 0:
            raise ValueError(f"options['position'] {tuple(float(v) for v in xy)} is not a recorded lattice cell")
        return xy


class BatchedNomadOfficeMemorable(BatchedNomadOffice):
    """``num_envs`` replay robots in one numpy call; sub-env ``i`` equals a seeded single env."""

    def __init__(
        self,
        num_envs: int,
        map: str | Path | None = None,
        *,
        database: str | Path | SensorDatabase | None = None,
        observe_odometry: bool = True,
        render_mode: str | None = None,
        max_episode_steps: int = MAX_EPISODE_STEPS,
        observation: str = "sensors",
    ) -> None:
        super().__init__(
            num_envs,
            map,
            observe_odometry=observe_odometry,
            render_mode=render_mode,
            max_episode_steps=max_episode_steps,
            observation=observation,
        )
        self.replay = _Replay(self.core, database)
        self._moves = self.replay.moves

    def _observe(self, rows: np.ndarray) -> np.ndarray:
        if self.observation == "cell":
            return super()._observe(rows)
        cells = self._cell[rows]
        obs = self._obs_table[cells]
        obs[:, : sensors.N_READINGS] = self.replay.draw(cells, self._key[rows], self._t[rows])
        return obs


def make_memorable_vec_env(n_envs: int, seed: int | None = None, **kwargs: Any) -> SB3VecEnvAdapter:
    """An SB3 ``VecEnv`` of ``n_envs`` batched ``NomadOfficeMemorable-v0`` robots."""
    return make_sb3_vec_env(n_envs, seed, batch_class=BatchedNomadOfficeMemorable, **kwargs)
