"""The factorial of ``docs/factorial.md``: which setting turns the paper's route result on: ``sb3-twodrl-factorial``.

Each cell is a folder of ``sb3-twodrl-ablation --set ...`` arms (``<runs>/<cell>/<arm>/``). This module
reads their rows and applies the registered metrics and rules; it runs nothing. Per run
(:func:`run_metrics`): learned, first epoch at a goal rate >= 0.5, the early detour share (epochs
1-150), the final detour and shortcut shares, reward per step and collision rate (last 10% of the
epochs), and the interest share. Per cell and arm: means with 95% intervals over seeds (Wilson for
the share that learned). Per cell: each 2D arm minus ``a2c`` with a Welch interval, and the rules'
verdicts. With ``--figures``, the paper's figures 3-5 per cell (extra ``plots``).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from sb3_twodrl.experiments.ablation import interval, summarize_run
from sb3_twodrl.experiments.grid import collect_results
from sb3_twodrl.experiments.intervals import welch_ci

EARLY_EPOCHS = 150
"""The paper's window for its actor-critic's detour (section 3.4): epochs 1-150."""
FINAL_SHARE = 0.1
"""The final metrics average the last 10% of a run's epochs."""
DETOUR_ON = 0.3
"""A2C's detour preference is on when the lower end of its early detour share's interval reaches this."""
METRICS = (
    "learned",
    "epochs_to_half",
    "early_detour_share",
    "final_detour_share",
    "final_shortcut_share",
    "reward_per_step",
    "collision_rate",
    "interest_share",
)


def run_metrics(rows: Any) -> dict[str, float]:
    """The registered metrics of one (arm, seed)'s rows, in epoch order (NaN shares are left out)."""
    summary = summarize_run(rows)
    n_final = max(1, round(FINAL_SHARE * len(rows)))
    final = rows.iloc[-n_final:]
    early = rows.loc[rows["epoch"] <= EARLY_EPOCHS, "detour_share"].to_numpy(dtype=float)

    def mean(values: np.ndarray) -> float:
        values = values[np.isfinite(values)]
        return float(values.mean()) if values.size else math.nan

    return {
        "learned": summary["learned"],
        "epochs_to_half": summary["epochs_to_half"],
        "early_detour_share": mean(early),
        "final_detour_share": mean(final["detour_share"].to_numpy(dtype=float)),
        "final_shortcut_share": mean(final["shortcut_share"].to_numpy(dtype=float)),
        "reward_per_step": mean(final["reward_per_step"].to_numpy(dtype=float)),
        "collision_rate": mean(final["collision_rate"].to_numpy(dtype=float)),
        "interest_share": summary["interest_share"],
    }


def cell_rows(runs: Path) -> dict[str, dict[str, Any]]:
    """Per cell folder of ``runs``, per arm folder with rows, its rows (:func:`collect_results`)."""
    cells = {}
    for cell in sorted(p for p in runs.iterdir() if p.is_dir()):
        arms = {arm.name: collect_results(arm) for arm in sorted(cell.iterdir()) if (arm / "pairs").is_dir()}
        if arms:
            cells[cell.name] = arms
    return cells


def read_cells(runs: Path) -> dict[str, dict[str, list[dict[str, float]]]]:
    """Per cell, per arm (:func:`cell_rows`), the :func:`run_metrics` of each seed."""
    cells = {
        cell: {
            arm: [{"seed": int(seed), **run_metrics(rows)} for seed, rows in df.groupby("seed")]
            for arm, df in arms.items()
        }
        for cell, arms in cell_rows(runs).items()
    }
    if not cells:
        raise ValueError(f"runs: no cell with rows under {runs}")
    return cells


def _cell(values: list[float], learned: bool) -> str:
    mean, low, high, n = interval(values, count=learned)
    if n == 0:
        return "-"
    if math.isnan(low):
        return f"{mean:.3f} (n={n})"
    return f"{mean:.3f} [{low:.3f}, {high:.3f}] (n={n})"


def table(cells: dict[str, dict[str, list[dict[str, float]]]]) -> str:
    """Markdown: one row per (cell, arm), each metric's mean [95% interval] (n seeds)."""
    lines = ["| cell | arm | " + " | ".join(METRICS) + " |", "|---" * (len(METRICS) + 2) + "|"]
    for cell, arms in cells.items():
        for arm, runs in arms.items():
            cells_md = [_cell([r[key] for r in runs], key == "learned") for key in METRICS]
            lines.append(f"| {cell} | {arm} | " + " | ".join(cells_md) + " |")
    return "\n".join(lines)


def verdicts(cells: dict[str, dict[str, list[dict[str, float]]]], baseline: str = "a2c") -> str:
    """Markdown: per cell, A2C's detour rule and, per 2D arm, its Welch differences and the shortcut rule."""
    lines = [
        "| cell | arm | A2C early detour on | final shortcut share minus A2C | reward per step minus A2C "
        "| shortcut advantage on |",
        "|---|---|---|---|---|---|",
    ]
    for cell, arms in cells.items():
        if baseline not in arms:
            continue
        base = arms[baseline]
        _, low, _, _ = interval([r["early_detour_share"] for r in base])
        detour_on = bool(low >= DETOUR_ON)
        for arm, runs in arms.items():
            if arm == baseline:
                continue
            diffs = []
            for key in ("final_shortcut_share", "reward_per_step"):
                a = [r[key] for r in runs if np.isfinite(r[key])]
                b = [r[key] for r in base if np.isfinite(r[key])]
                diffs.append(welch_ci(a, b) if len(a) > 1 and len(b) > 1 else (math.nan, math.nan))
            (share, half), (reward, reward_half) = diffs
            on = bool(share - half > 0)
            lines.append(
                f"| {cell} | {arm} | {detour_on} | {share:+.3f} [{share - half:+.3f}, {share + half:+.3f}] "
                f"| {reward:+.4f} [{reward - reward_half:+.4f}, {reward + reward_half:+.4f}] | {on} |"
            )
    return "\n".join(lines)


def figures(runs: Path, out: Path) -> list[Path]:
    """The paper's figures 3-5 of each cell, every arm's seeds (:func:`~sb3_twodrl.experiments.plots.make_figures`):
    ``<out>/<cell>/fig*.png``."""
    import pandas as pd

    from sb3_twodrl.experiments.plots import make_figures

    paths = []
    for cell, arms in cell_rows(runs).items():
        df = pd.concat(arms.values(), ignore_index=True)
        seeds = ", ".join(f"{algo} {g['seed'].nunique()}" for algo, g in df.groupby("algo"))
        paths += make_figures(df, out / cell, title=f"factorial cell {cell} (seeds: {seeds})")
    return paths


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=Path, default=Path("runs") / "factorial", help="folder of the cell folders")
    p.add_argument("--out", type=Path, help="also write table.md and runs.json here")
    p.add_argument("--figures", action="store_true", help="with --out: also the figures 3-5 of each cell")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    cells = read_cells(args.runs)
    text = table(cells) + "\n\n" + verdicts(cells) + "\n"
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "table.md").write_text(text)
        (args.out / "runs.json").write_text(json.dumps(cells, indent=1))
        if args.figures:
            figures(args.runs, args.out)
    print(text)
