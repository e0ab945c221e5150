"""The gap between the ideal simulator and the stand-in robot, measured before any learning."""

from __future__ import annotations

import numpy as np

from twodrl_envs.nomad.core import OfficeCore
from twodrl_envs.nomad.geometry import MOVES_CM
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import HIGH_CM, LOW_CM


def systematic_difference(core: OfficeCore, model: RealisticModel, draws: int, seed: int) -> np.ndarray:
    """``|median over draws of the realistic ranges - the ideal ranges|`` ``(n_reachable, 32)`` cm.

    Both models read at the same poses, the reachable lattice cells; each draw is a fresh episode
    key at step 0, so the median removes per-ping noise and keeps what depends on pose and walls.
    """
    if isinstance(draws, bool) or not isinstance(draws, int) or draws < 1:
        raise ValueError(f"draws must be a positive int, got {draws!r}")
    cells = core.lattice.cells[core.lattice.reachable]
    scene = model.scene(core.office)
    cached = scene.deterministic(cells)
    rng = np.random.default_rng(seed)
    steps = np.zeros(len(cells), dtype=np.int64)
    samples = [
        scene.ranges(cells, rng.integers(0, 2**63, len(cells), dtype=np.uint64), steps, cached) for _ in range(draws)
    ]
    ideal = np.clip(core.ranges[core.lattice.reachable], LOW_CM, HIGH_CM)
    return np.abs(np.median(np.stack(samples), axis=0) - ideal)


def odometry_errors(model: RealisticModel, moves: int, robots: int, seed: int, straight: bool = False) -> np.ndarray:
    """Dead-reckoning error ``(moves, robots)`` cm after each of ``moves`` commanded moves (no walls).

    The moves are uniformly random, or with ``straight`` all in one random direction per robot (a
    corridor run, where the systematic part adds up instead of cancelling).
    """
    rng = np.random.default_rng(seed)
    keys = rng.integers(0, 2**63, robots, dtype=np.uint64)
    heading = rng.integers(0, 4, robots)
    error = np.zeros((robots, 2))
    out = np.empty((moves, robots))
    for step in range(1, moves + 1):
        actions = heading if straight else rng.integers(0, 4, robots)
        error += model.displacement(actions, keys, np.full(robots, step)) - MOVES_CM[actions]
        out[step - 1] = np.linalg.norm(error, axis=1)
    return out


def k_convergence(core: OfficeCore, model: RealisticModel, ks: tuple[int, ...], reference: int, seed: int) -> dict:
    """How many recorded readings per cell (K) a database needs to show a cell's typical sonar reading.

    Records ``reference`` tours by dead reckoning (:func:`twodrl_envs.memorable.recording.drive_and_record`)
    and returns, per ``K`` in ``ks``, the share of (reachable cell, sonar) pairs whose median over the
    first ``K`` readings differs by more than 50 cm from the median over all ``reference`` readings.
    """
    from twodrl_envs.memorable.recording import drive_and_record

    counts, per_cell, _ = drive_and_record(core, model, reference, seed)
    cells = [r[:, :16] for r, c in zip(per_cell, counts, strict=True) if c >= reference]
    full = np.stack([np.median(r, axis=0) for r in cells])
    return {k: float(np.mean(np.abs(np.stack([np.median(r[:k], axis=0) for r in cells]) - full) > 50)) for k in ks}
