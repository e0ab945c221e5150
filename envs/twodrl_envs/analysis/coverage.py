"""How much of a map an imported database covers: the reachable cells with readings, the readings per cell, and a
picture (``sb3-twodrl-record-database`` reports it after ``--from-bag`` or ``--from-csv``; the picture needs
matplotlib, extra ``sb3-twodrl[plots]``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twodrl_envs.memorable.database import SensorDatabase
from twodrl_envs.nomad.core import OfficeCore

PLOTS_HINT = 'the coverage picture needs matplotlib: pip install "sb3-twodrl[plots]"'


@dataclass(frozen=True)
class Coverage:
    """A database's coverage of its map's lattice."""

    reachable: int  # lattice cells reachable from the start
    covered: int  # reachable cells with readings
    unreachable_covered: int  # cells with readings that the start cannot reach
    missing_cm: np.ndarray  # (m, 2): the reachable cells without readings, cm
    per_cell: tuple[int, float, int]  # readings per reachable cell: min, median, max

    def describe(self) -> str:
        """Two lines at most: cells covered, readings per cell, and the missing cells' first positions."""
        low, median, high = self.per_cell
        lines = [
            f"coverage: {self.covered} of {self.reachable} reachable cells have readings "
            f"({100 * self.covered / self.reachable:.0f}%); readings per reachable cell: "
            f"min {low}, median {median:g}, max {high}"
        ]
        notes = []
        if len(self.missing_cm):
            notes.append(f"{len(self.missing_cm)} without readings, e.g. {self.missing_examples()}")
        if self.unreachable_covered:
            notes.append(f"{self.unreachable_covered} cells with readings that the start cannot reach")
        if notes:
            lines.append("  " + "; ".join(notes))
        return "\n".join(lines)

    def missing_examples(self, n: int = 5) -> str:
        return ", ".join(f"({x:g}, {y:g})" for x, y in self.missing_cm[:n])


def _check_cells(db: SensorDatabase, core: OfficeCore) -> None:
    if not np.array_equal(db.cells, core.lattice.cells):
        raise ValueError(f"database: its cell list does not match the lattice of map {core.office.source}")


def coverage(db: SensorDatabase, core: OfficeCore) -> Coverage:
    """The coverage of ``core``'s lattice by ``db`` (a database of that map, complete or not)."""
    _check_cells(db, core)
    reachable = core.lattice.reachable
    counts = db.counts[reachable]
    return Coverage(
        reachable=int(reachable.sum()),
        covered=int((counts > 0).sum()),
        unreachable_covered=int((db.counts[~reachable] > 0).sum()),
        missing_cm=db.cells[reachable & (db.counts == 0)],
        per_cell=(int(counts.min()), float(np.median(counts)), int(counts.max())),
    )


def plot_coverage(db: SensorDatabase, core: OfficeCore, path: str | Path) -> Path:
    """Draw the map's walls and each lattice cell coloured by its readings (reachable cells without readings
    red, crossed) to the PNG ``path``; ``ModuleNotFoundError`` naming the extra without matplotlib."""
    try:
        import matplotlib
    except ImportError as err:
        raise ModuleNotFoundError(f"{PLOTS_HINT} ({err})", name="matplotlib") from err
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _check_cells(db, core)
    office, cells, counts = core.office, db.cells, db.counts
    missing = core.lattice.reachable & (counts == 0)
    x0, y0, x1, y1 = office.bounds
    fig, ax = plt.subplots(figsize=(6.4, 6.4 * (y1 - y0) / (x1 - x0) + 0.8), dpi=120)
    for xa, ya, xb, yb in office.walls:
        ax.plot([xa, xb], [ya, yb], color="black", linewidth=1.5)
    shown = counts > 0
    dots = ax.scatter(cells[shown, 0], cells[shown, 1], c=counts[shown], s=9, marker="s", cmap="viridis", vmin=0)
    ax.scatter(
        cells[missing, 0], cells[missing, 1], color="red", s=14, marker="x", label=f"no readings ({int(missing.sum())})"
    )
    ax.plot(*office.start, marker="*", color="orange", markersize=12, linestyle="", label="start")
    fig.colorbar(dots, ax=ax, label="readings per cell", shrink=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    ax.set_title(
        f"{office.name}: {int((shown & core.lattice.reachable).sum())} of {int(core.lattice.reachable.sum())} "
        "reachable cells have readings",
        fontsize=9,
    )
    gx0, gy0, gx1, gy1 = office.regions["goal"]
    ax.add_patch(
        plt.Rectangle((gx0, gy0), gx1 - gx0, gy1 - gy0, fill=False, color="green", linestyle="--", label="goal")
    )
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=7, frameon=False)
    path = Path(path)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path
