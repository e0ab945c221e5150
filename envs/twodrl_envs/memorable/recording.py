"""Recording a sensor database as a real robot would: driving by dead reckoning.

A real robot does not know where it is: it labels each recording with its odometry. The
recorder below drives the stand-in robot of :mod:`twodrl_envs.nomad.realistic` from the map's start to
every reachable lattice cell along the shortest lattice path, commanding 10 cm moves; the robot's
true pose drifts (slip, scale and misalignment errors), the reading is taken at the true pose and
filed under the cell its odometry reports. Each of the ``k`` tours drives every cell once, with
fresh episode keys, so a cell's ``k`` readings come from ``k`` independent drifts and pings.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.memorable.database import SensorDatabase, database_metadata
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import OfficeCore, office_core
from twodrl_envs.nomad.geometry import ROBOT_RADIUS_CM, swept_clearance
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import HIGH_CM, LOW_CM


def shortest_paths(core: OfficeCore) -> list[list[int]]:
    """Per lattice cell, the actions of a shortest collision-free lattice path from the start (empty if unreachable)."""
    moves = core.lattice.moves
    parent = np.full(len(moves), -1)
    action = np.full(len(moves), -1)
    seen = np.zeros(len(moves), dtype=bool)
    seen[core.start_cell] = True
    frontier = [core.start_cell]
    while frontier:
        nxt = []
        for cell in frontier:
            for a, target in enumerate(moves[cell]):
                if target >= 0 and not seen[target]:
                    seen[target], parent[target], action[target] = True, cell, a
                    nxt.append(int(target))
        frontier = nxt
    paths: list[list[int]] = []
    for cell in range(len(moves)):
        path: list[int] = []
        while parent[cell] >= 0:
            path.append(int(action[cell]))
            cell = int(parent[cell])
        paths.append(path[::-1])
    return paths


Log = Callable[[np.ndarray, np.ndarray], None]
"""Called with the odometry positions ``(m, 2)`` cm and the readings ``(m, 32)`` cm of each batch the recorder files,
in filing order: the drive as the robot would log it (``twodrl_envs.analysis.bags.write_bag`` writes it as a bag)."""


def drive_and_record(
    core: OfficeCore,
    model: RealisticModel,
    k: int,
    seed: int,
    max_tries: int = 20,
    log: Log | None = None,
    progress: bool = False,
) -> tuple[np.ndarray, list[np.ndarray], dict[str, Any]]:
    """``k`` tours over the reachable cells; returns ``(counts, readings per cell, statistics)``.

    A run whose true pose bumps into a wall is driven again with fresh keys (the operator puts the
    robot back at the start), up to ``max_tries`` times; a cell whose run never succeeds gets fewer
    than ``k`` readings. ``log`` (:data:`Log`) sees each batch of readings as it is filed; ``progress`` shows a
    bar of the tours.
    """
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ValueError(f"k must be a positive int, got {k!r}")
    scene = model.scene(core.office)
    walls = core.office.walls
    cells = np.flatnonzero(core.lattice.reachable)
    paths = shortest_paths(core)
    length = np.array([len(paths[c]) for c in cells])
    plan = np.full((len(cells), max(int(length.max()), 1)), -1)
    for row, cell in enumerate(cells):
        plan[row, : length[row]] = paths[cell]
    start = np.array(core.office.start, dtype=np.float64)
    rng = np.random.default_rng(seed)
    per_cell: list[list[np.ndarray]] = [[] for _ in range(len(core.lattice.cells))]
    bumps, errors = 0, []
    tours: Any = range(k)
    if progress:
        from tqdm import tqdm

        tours = tqdm(tours, desc=f"recording {len(cells)} cells", unit="tour")
    for _ in tours:
        todo = np.arange(len(cells))
        for _ in range(max_tries):
            if len(todo) == 0:
                break
            keys = rng.integers(0, 2**63, len(todo), dtype=np.uint64)
            pos = np.repeat(start[None], len(todo), axis=0)
            ok = np.ones(len(todo), dtype=bool)
            for step in range(plan.shape[1]):
                moving = ok & (step < length[todo])
                if not moving.any():
                    break
                rows = np.flatnonzero(moving)
                actions = plan[todo[rows], step]
                target = pos[rows] + model.displacement(actions, keys[rows], np.full(len(rows), step + 1))
                clear = (swept_clearance(pos[rows], target, walls) > ROBOT_RADIUS_CM) & core.office.inside_bounds(
                    target
                )
                pos[rows[clear]] = target[clear]
                ok[rows[~clear]] = False
            bumps += int((~ok).sum())
            done = np.flatnonzero(ok)
            readings = scene.ranges(pos[done], keys[done], length[todo[done]] + 1)
            odometry = core.lattice.cells[cells[todo[done]]]
            errors.extend(np.linalg.norm(pos[done] - odometry, axis=1).tolist())
            reported = np.clip(readings, LOW_CM, HIGH_CM)
            if log is not None:
                log(odometry, reported)
            for row, reading in zip(todo[done], reported, strict=True):
                per_cell[cells[row]].append(reading)
            todo = todo[~ok]
    counts = np.array([len(r) for r in per_cell], dtype=np.int64)
    stats = {
        "tours": k,
        "bumped_runs": bumps,
        "cells_short_of_k": int(((counts < k) & core.lattice.reachable).sum()),
        "median_odometry_error_cm": float(np.median(errors)),
        "p95_odometry_error_cm": float(np.percentile(errors, 95)),
    }
    return counts, [np.array(r).reshape(-1, 32) for r in per_cell], stats


def record_database(
    k: int,
    *,
    map: str | Path | None = None,
    noise: sensors.NoiseModel | None = None,
    seed: int = 0,
    progress: bool = False,
    model: RealisticModel | None = None,
    log: Log | None = None,
) -> SensorDatabase:
    """Record ``k`` readings per reachable cell of a virtual robot.

    With ``model`` (a :class:`~twodrl_envs.nomad.realistic.RealisticModel`, the stand-in robot of
    ``NomadOfficeReal-v0``) the robot records as a real one would: it drives to each cell by dead
    reckoning and files the reading taken at its drifted true pose under its odometry's cell
    (:func:`drive_and_record`). Otherwise it is placed exactly on each
    cell: ``noise=None`` records the ideal (exact) sensors, a
    :class:`~twodrl_envs.nomad.sensors.NoiseModel` adds per-reading noise to them. Readings are saturated
    to the sensors' ranges as a real robot reports them. Unreachable free cells get no readings. ``log``
    (:data:`Log`) sees the readings and the positions they are filed under, in filing order.
    """
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ValueError(f"k must be a positive int, got {k!r}")
    if model is not None and not isinstance(model, RealisticModel):
        raise TypeError(f"model must be a RealisticModel or None, got {type(model).__name__}: {model!r}")
    if model is not None and noise is not None:
        raise ValueError("pass either model (the stand-in robot) or noise (noisy ideal sensors), not both")
    core = office_core(map)
    if model is not None:
        counts, per_cell, stats = drive_and_record(core, model, k, seed, log=log, progress=progress)
        recording = {
            "source": "simulated",
            "sensor_model": "realistic (twodrl_envs.nomad.realistic.RealisticModel, NomadOfficeReal-v0)",
            "model": model.describe(),
            "samples_per_cell": k,
            "seed": seed,
            "how": "stand-in robot driven from the start to every reachable cell by dead reckoning, once per tour; "
            "each reading taken at the drifted true pose, filed under the odometry's cell",
            **stats,
        }
        ranges = np.concatenate([r for r in per_cell if len(r)], axis=0)
        return SensorDatabase(core.lattice.cells.copy(), counts, ranges, database_metadata(core, recording))
    rng = np.random.default_rng(seed)
    cells = np.flatnonzero(core.lattice.reachable)
    counts = np.where(core.lattice.reachable, k, 0).astype(np.int64)
    rows = []
    iterator: Any = cells
    if progress:
        from tqdm import tqdm

        iterator = tqdm(cells, desc="recording cells", unit="cell")
    for cell in iterator:
        exact = np.repeat(core.ranges[cell : cell + 1], k, axis=0)
        if noise is not None:
            exact = noise.sample(exact, rng)
        rows.append(np.clip(exact, LOW_CM, HIGH_CM))
        if log is not None:
            log(np.repeat(core.lattice.cells[cell : cell + 1], k, axis=0), rows[-1])
    recording = {
        "source": "simulated",
        "sensor_model": "ideal" if noise is None else "noisy ideal (twodrl_envs.nomad.sensors.NoiseModel)",
        "noise_model": None if noise is None else asdict(noise),
        "samples_per_cell": k,
        "seed": seed,
        "how": "virtual robot placed on every reachable lattice cell, k independent noisy readings per cell",
    }
    return SensorDatabase(
        core.lattice.cells.copy(), counts, np.concatenate(rows, axis=0), database_metadata(core, recording)
    )
