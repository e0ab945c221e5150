"""The factorial of ``docs/factorial.md``: which setting turns the paper's route result on: its report.

Each cell is a part of the study (spec ``factorial/<cell>``, run folder ``runs/factorial/<cell>``). This
report reads their rows and applies the registered metrics and rules (:data:`RULES`, which every cell's
spec states under ``rules``: a cell stating others is refused). Per run
(:func:`run_metrics`): learned, first epoch at a goal rate >= 0.5, the early detour share (epochs
1-150), the final detour and shortcut shares, reward per step and collision rate (last 10% of the
epochs), and the interest share. Per cell and arm: means with 95% intervals over seeds (Wilson for
the share that learned). Per cell: each 2D arm minus ``a2c`` with a Welch interval, and the rules'
verdicts; per cell run to 1000 epochs, whether the paper's figures 3-5 reappear (:func:`paper_result`),
read only once both arms have every seed (amendment 8). Across the exploration-bonus cells
(``ent0``, ``ent0.01``, ``ent0.05``): the test of "the interest replaces a tuned entropy bonus"
(:func:`bonus_claim`). The paper's figures 3-5 per cell; for each ``rules.read_at_epochs`` N, the
tables of every cell read up to epoch N (amendment 12) in ``at_epoch<N>/``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_bench.intervals import welch_ci, wilson
from twodrl_bench.reports import Part
from twodrl_bench.reports.ablation import interval, summarize_run

EARLY_EPOCHS = 150
"""The paper's window for its actor-critic's detour (section 3.4): epochs 1-150."""
FINAL_SHARE = 0.1
"""The final metrics average the last 10% of a run's epochs."""
DETOUR_ON = 0.3
"""A2C's detour preference is on when the lower end of its early detour share's interval reaches this."""
BONUS_CELLS = {"ent0": 0.0, "ent0.01": 0.01, "ent0.05": 0.05}
"""The exploration-bonus cells at 64 envs and MLP, by folder name, and their ``ent_coef``."""
REWARD_MARGIN = 0.005
"""The bonus claim's margin on reward per step: about 2% of the protocol's 0.28."""
SEEDS_PER_CELL = 10
"""The registered seeds per (cell, arm); a rule on fewer is provisional."""
PROTOCOL_CELL = "ent0.05"
"""The cell at the protocol's shared settings, against which each factor's effect is measured."""
LONG_EPOCHS = 1000
"""The extension's length: a cell whose runs reach it is read by :func:`paper_result`."""
PAPER_WINDOW = (151, 400)
"""Epochs over which A2C's detour share must reach :data:`PAPER_SHARE` for the paper's figures to reappear."""
PAPER_SHARE = 0.5
"""The detour share (A2C, :data:`PAPER_WINDOW`) and final shortcut share (2D arm) the paper's result needs."""
EFFECT_METRICS = ("early_detour_share", "final_shortcut_share", "reward_per_step")
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


RULES: dict[str, Any] = {
    "early_epochs": EARLY_EPOCHS,
    "final_share": FINAL_SHARE,
    "detour_on": DETOUR_ON,
    "bonus_cells": BONUS_CELLS,
    "reward_margin": REWARD_MARGIN,
    "seeds_per_cell": SEEDS_PER_CELL,
    "protocol_cell": PROTOCOL_CELL,
    "long_epochs": LONG_EPOCHS,
    "paper_window": list(PAPER_WINDOW),
    "paper_share": PAPER_SHARE,
}
"""The registered rules (``docs/factorial.md``) as every cell's spec states them (plus ``read_at_epochs``)."""


def check_rules(parts: list[Part]) -> list[int]:
    """Refuse a cell whose spec states other rules than :data:`RULES`; the ``read_at_epochs`` of the cells.

    :raises ValueError: naming the cell and the differing rule
    """
    from twodrl_bench.spec import diff

    at: set[int] = set()
    for part in parts:
        rules = dict(part.spec["rules"])
        at |= set(rules.pop("read_at_epochs", []))
        differences = diff(RULES, rules)
        if differences:
            raise ValueError(f"{part.name}: rules differ from the registered ones: {'; '.join(differences)}")
    return sorted(at)


def run_metrics(rows: Any) -> dict[str, float]:
    """The registered metrics of one (arm, seed)'s rows, in epoch order (NaN shares are left out)."""
    summary = summarize_run(rows)
    n_final = max(1, round(FINAL_SHARE * len(rows)))
    final = rows.iloc[-n_final:]
    early = rows.loc[rows["epoch"] <= EARLY_EPOCHS, "detour_share"].to_numpy(dtype=float)
    epochs = int(rows["epoch"].max())
    first, last = PAPER_WINDOW
    window = rows.loc[rows["epoch"].between(first, last), "detour_share"].to_numpy(dtype=float)

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
        "epochs": epochs,
        "window_detour_share": mean(window) if epochs >= last else math.nan,
    }


def cell_rows(parts: list[Part], epochs: int | None = None) -> dict[str, dict[str, Any]]:
    """Per cell (part), per arm with rows, its rows in epoch order, with ``epochs`` only those up to that
    epoch (longer cells read at a shorter cell's length, amendment 12)."""
    if epochs is not None and epochs < 1:
        raise ValueError(f"epochs must be >= 1, got {epochs}")
    cells = {}
    for part in sorted(parts, key=lambda p: p.part):
        if part.rows.empty:
            continue
        rows = part.rows if epochs is None else part.rows[part.rows["epoch"] <= epochs]
        arms = {arm: g.reset_index(drop=True) for arm, g in rows.groupby("arm", sort=True)}
        if arms:
            cells[part.part] = arms
    return cells


def read_cells(parts: list[Part], epochs: int | None = None) -> dict[str, dict[str, list[dict[str, float]]]]:
    """Per cell, per arm (:func:`cell_rows`, up to ``epochs``), the :func:`run_metrics` of each seed."""
    cells = {
        cell: {
            arm: [{"seed": int(seed), **run_metrics(rows)} for seed, rows in df.groupby("seed")]
            for arm, df in arms.items()
        }
        for cell, arms in cell_rows(parts, epochs).items()
    }
    if not cells:
        raise ValueError(f"factorial: no cell with rows among {[p.name for p in parts]}")
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


def seeds_table(cells: dict[str, dict[str, list[dict[str, float]]]]) -> str:
    """Markdown: one row per (cell, arm, seed), each metric of :func:`run_metrics` ("-" where undefined)."""
    lines = ["| cell | arm | seed | " + " | ".join(METRICS) + " |", "|---" * (len(METRICS) + 3) + "|"]
    for cell, arms in cells.items():
        for arm, runs in arms.items():
            for run in runs:
                values = ["-" if math.isnan(run[key]) else f"{run[key]:.3f}" for key in METRICS]
                lines.append(f"| {cell} | {arm} | {run['seed']} | " + " | ".join(values) + " |")
    return "\n".join(lines)


def _welch(a: list[dict[str, float]], b: list[dict[str, float]], key: str) -> tuple[float, float, float]:
    """``key``'s mean over ``a`` minus over ``b`` and its 95% Welch interval, NaNs left out (NaN if a side
    has fewer than two runs)."""
    x, y = [r[key] for r in a if np.isfinite(r[key])], [r[key] for r in b if np.isfinite(r[key])]
    if len(x) < 2 or len(y) < 2:
        return math.nan, math.nan, math.nan
    diff, half = welch_ci(x, y)
    return diff, diff - half, diff + half


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
            if (short := _unread(base, runs)) is not None:
                lines.append(f"| {cell} | {arm} | {short} | - | - | {short} |")
                continue
            share = _welch(runs, base, "final_shortcut_share")
            reward = _welch(runs, base, "reward_per_step")
            lines.append(
                f"| {cell} | {arm} | {detour_on} | {_format(share)} | {_format(reward, 4)} | {bool(share[1] > 0)} |"
            )
    return "\n".join(lines)


def _unread(base: list[dict[str, float]], runs: list[dict[str, float]]) -> str | None:
    """Why a long cell's rules are not read yet: its arms short of seeds (amendment 8); None otherwise."""
    if max(r["epochs"] for r in base + runs) < LONG_EPOCHS or min(len(base), len(runs)) >= SEEDS_PER_CELL:
        return None
    return f"not read ({len(base)} and {len(runs)} of {SEEDS_PER_CELL} seeds)"


def paper_result(
    cells: dict[str, dict[str, list[dict[str, float]]]], arm: str = "twoda2c", baseline: str = "a2c"
) -> str:
    """Markdown: per cell run to :data:`LONG_EPOCHS`, whether the paper's figures 3-5 reappear.

    They do if A2C's mean detour share over :data:`PAPER_WINDOW` is at least :data:`PAPER_SHARE`, and
    ``arm``'s mean final shortcut share is at least :data:`PAPER_SHARE` with its Welch difference from
    A2C's wholly above 0. Read only once both arms have :data:`SEEDS_PER_CELL` seeds of that length.
    """
    lines = [
        f"| cell | A2C detour share, epochs {PAPER_WINDOW[0]}-{PAPER_WINDOW[1]} | {arm} final shortcut share "
        "| final shortcut share minus A2C | paper's figures reappear |",
        "|---|---|---|---|---|",
    ]
    for cell, arms in cells.items():
        base = [r for r in arms.get(baseline, []) if r["epochs"] >= LONG_EPOCHS]
        runs = [r for r in arms.get(arm, []) if r["epochs"] >= LONG_EPOCHS]
        if not base and not runs:
            continue
        detour = _cell([r["window_detour_share"] for r in base], False)
        shortcut = _cell([r["final_shortcut_share"] for r in runs], False)
        if min(len(base), len(runs)) < SEEDS_PER_CELL:
            lines.append(f"| {cell} | {detour} | {shortcut} | - | {_unread(base, runs)} |")
            continue
        share = _welch(runs, base, "final_shortcut_share")
        on = (
            np.nanmean([r["window_detour_share"] for r in base]) >= PAPER_SHARE
            and np.nanmean([r["final_shortcut_share"] for r in runs]) >= PAPER_SHARE
            and share[1] > 0
        )
        lines.append(f"| {cell} | {detour} | {shortcut} | {_format(share)} | {bool(on)} |")
    return "\n".join(lines)


def _format(difference: tuple[float, float, float], digits: int = 3) -> str:
    """``+d [+low, +high]`` of a :func:`_welch` difference; "-" where it is undefined."""
    diff, low, high = difference
    return "-" if math.isnan(diff) else f"{diff:+.{digits}f} [{low:+.{digits}f}, {high:+.{digits}f}]"


def effects(cells: dict[str, dict[str, list[dict[str, float]]]], reference: str = PROTOCOL_CELL) -> str:
    """Markdown: each cell's effect against ``reference`` per arm in both: seeds learned, and the Welch
    interval of (cell minus reference) on each of :data:`EFFECT_METRICS`."""
    heads = " | ".join(f"{key} minus reference" for key in EFFECT_METRICS)
    lines = [
        f"| cell | arm | learned (cell vs reference) | {heads} |",
        "|---" * (len(EFFECT_METRICS) + 3) + "|",
    ]
    for cell, arms in cells.items():
        for arm, runs in arms.items():
            base = cells.get(reference, {}).get(arm)
            if cell == reference or base is None:
                continue
            (k1, n1, _), (k2, n2, _) = _learned(runs), _learned(base)
            diffs = " | ".join(_format(_welch(runs, base, key)) for key in EFFECT_METRICS)
            lines.append(f"| {cell} | {arm} | {k1}/{n1} vs {k2}/{n2} | {diffs} |")
    return "\n".join(lines)


def _learned(runs: list[dict[str, float]]) -> tuple[int, int, tuple[float, float]]:
    k, n = int(sum(r["learned"] for r in runs)), len(runs)
    return k, n, wilson(k, n)


def check_bonus_cells(parts: list[Part]) -> None:
    """Refuse a :data:`BONUS_CELLS` cell whose arms run at another ``ent_coef`` than its name says."""
    for part in parts:
        coef = BONUS_CELLS.get(part.part)
        if coef is None:
            continue
        for arm, settings in part.spec["arms"].items():
            value = settings["hyperparams"].get("ent_coef", math.nan)
            if float(value) != coef:
                raise ValueError(f"cell {part.part!r} arm {arm!r} has ent_coef {value!r}")


def bonus_claim(cells: dict[str, dict[str, list[dict[str, float]]]], arm: str = "twoda2c") -> str:
    """Markdown: the registered test of "the interest replaces a tuned entropy bonus".

    A2C's best ``ent_coef`` is the :data:`BONUS_CELLS` cell with its highest mean reward per step. The
    claim holds if ``arm`` at ``ent_coef`` 0 is within :data:`REWARD_MARGIN` of it (Welch lower bound)
    and learns on as many seeds, or on a share whose Wilson interval overlaps. It is informative only
    if the bonus matters to A2C: ``a2c`` at 0 worse than at its best by a resolved Welch interval, or
    learning on fewer seeds with disjoint Wilson intervals. Provisional while a cell lacks seeds.
    """
    a2c = {cell: cells[cell]["a2c"] for cell in BONUS_CELLS if "a2c" in cells.get(cell, {})}
    if "ent0" not in a2c or arm not in cells["ent0"]:
        return f"Bonus claim: not testable yet (needs `a2c` and `{arm}` in cell `ent0`)."
    best = max(a2c, key=lambda cell: float(np.mean([r["reward_per_step"] for r in a2c[cell]])))
    ours, theirs, bare = cells["ent0"][arm], a2c[best], a2c["ent0"]
    diff, low, high = _welch(ours, theirs, "reward_per_step")
    (k1, n1, w1), (k2, n2, w2) = _learned(ours), _learned(theirs)
    holds = low > -REWARD_MARGIN and (k1 / n1 >= k2 / n2 or (w1[0] <= w2[1] and w2[0] <= w1[1]))
    if best == "ent0":
        matters, why = False, "A2C's best bonus is 0"
    else:
        _, _, bare_high = _welch(bare, theirs, "reward_per_step")
        (_, _, wb), (_, _, wt) = _learned(bare), _learned(theirs)
        matters = bare_high < 0 or wb[1] < wt[0]
        why = (
            f"`a2c` at 0 minus at its best, reward per step upper bound {bare_high:+.4f}; learned "
            f"[{wb[0]:.2f}, {wb[1]:.2f}] vs [{wt[0]:.2f}, {wt[1]:.2f}]"
        )
    missing = [cell for cell in BONUS_CELLS if cell not in a2c]
    missing += [f"{cell}/a2c" for cell, runs in a2c.items() if len(runs) < SEEDS_PER_CELL]
    missing += [f"ent0/{arm}"] if len(ours) < SEEDS_PER_CELL else []
    verdict = ("holds" if holds else "fails") if matters else "untested: the entropy bonus does not matter to A2C here"
    return (
        f"Bonus claim (`{arm}` at `ent_coef` 0 against `a2c` at its best, `{best}`): **{verdict}**"
        + (f" (provisional: short of {SEEDS_PER_CELL} seeds or cells: {', '.join(missing)})" if missing else "")
        + f". Reward per step difference {diff:+.4f} [{low:+.4f}, {high:+.4f}]; learned {k1}/{n1} "
        f"[{w1[0]:.2f}, {w1[1]:.2f}] vs {k2}/{n2} [{w2[0]:.2f}, {w2[1]:.2f}]; bonus matters: {matters} ({why})."
    )


def figures(parts: list[Part], out: Path, epochs: int | None = None) -> list[Path]:
    """The paper's figures 3-5 of each cell, every arm's seeds up to ``epochs``
    (:func:`~twodrl_bench.plots.make_figures`): ``<out>/<cell>/fig*.png``."""
    import pandas as pd

    from twodrl_bench.plots import make_figures

    paths = []
    for cell, arms in cell_rows(parts, epochs).items():
        df = pd.concat(arms.values(), ignore_index=True).assign(algo=lambda d: d["arm"])
        seeds = ", ".join(f"{arm} {g['seed'].nunique()}" for arm, g in df.groupby("algo"))
        paths += make_figures(df, out / cell, title=f"factorial cell {cell} (seeds: {seeds})")
    return paths


def tables(cells: dict[str, dict[str, list[dict[str, float]]]]) -> str:
    """The registered tables and verdicts of ``cells``."""
    parts = [
        table(cells),
        verdicts(cells),
        bonus_claim(cells),
        f"Cells run to {LONG_EPOCHS} epochs: do the paper's figures 3-5 reappear?",
        paper_result(cells),
        f"Effects against the protocol's cell `{PROTOCOL_CELL}`:",
        effects(cells),
        "Per seed:",
        seeds_table(cells),
    ]
    return "\n\n".join(parts) + "\n"


def report(parts: list[Part], out: Path) -> str:
    """Write ``table.md``, ``runs.json`` and each cell's figures under ``out`` (and ``at_epoch<N>/`` for each
    ``rules.read_at_epochs``); the tables."""
    at = check_rules(parts)
    check_bonus_cells(parts)
    for epochs, folder in [(None, out), *((n, out / f"at_epoch{n}") for n in at)]:
        cells = read_cells(parts, epochs)
        text = tables(cells)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "table.md").write_text(text)
        (folder / "runs.json").write_text(json.dumps(cells, indent=1))
    figures(parts, out)
    return (out / "table.md").read_text()
