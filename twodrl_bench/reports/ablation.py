"""What each part of 2D-RL contributes (``docs/ablation.md``): the ablation's report.

Per run (:func:`summarize_run`): final test goal rate (last epoch), learned (final goal rate >=
:data:`~sb3_twodrl.callbacks.SUCCESS_THRESHOLD`, 0.8), the first epoch with a goal rate >= 0.5, shortcut share and
reward per step of the last epoch, collapse (after a goal rate >= the threshold, 3 or more consecutive epochs below
0.5), and, over all learning
steps, the share on which the interest, not a clamp, set the temperature. Per arm (:func:`table`):
means over seeds with 95% intervals (t over seeds; Wilson for the share of seeds that learned).
The fixed arms act at ``rules.fixed_temperature.value``; the report measures ``rules.fixed_temperature.arm``'s
mean temperature from its rows (:func:`mean_temperature`) and says whether it rounds to that value.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from sb3_twodrl.callbacks import SUCCESS_THRESHOLD
from twodrl_bench.intervals import mean_ci, wilson
from twodrl_bench.reports import Part

METRICS = (
    "learned",
    "final_goal_rate",
    "epochs_to_half",
    "shortcut_share",
    "reward_per_step",
    "interest_share",
)


def mean_temperature(rows: Any) -> float:
    """Mean temperature over all learning steps of ``rows`` (a results DataFrame), weighted by steps."""
    steps = rows.groupby("seed")["env_steps"].diff().fillna(rows["env_steps"])
    keep = rows["mean_temperature"].notna()
    if not keep.any():
        raise ValueError("rows have no mean_temperature: the paper arm has not run")
    return float(np.average(rows.loc[keep, "mean_temperature"], weights=steps[keep]))


def summarize_run(rows: Any) -> dict[str, float]:
    """The per-run metrics of one (arm, seed)'s rows, in epoch order."""
    rates = rows["goal_rate"].to_numpy(dtype=float)
    steps = np.diff(rows["env_steps"].to_numpy(dtype=float), prepend=0.0)
    share = rows["interest_share"].to_numpy(dtype=float)
    known = ~np.isnan(share)
    half = np.flatnonzero(rates >= 0.5)
    peak = np.flatnonzero(rates >= SUCCESS_THRESHOLD)
    longest = run = 0
    for below in rates[peak[0] :] < 0.5 if peak.size else []:
        run = run + 1 if below else 0
        longest = max(longest, run)
    last = rows.iloc[-1]
    return {
        "learned": float(rates[-1] >= SUCCESS_THRESHOLD),
        "final_goal_rate": float(rates[-1]),
        "epochs_to_half": float(half[0] + 1) if half.size else math.nan,
        "shortcut_share": float(last["shortcut_share"]),
        "reward_per_step": float(last["reward_per_step"]),
        "interest_share": float(np.average(share[known], weights=steps[known])) if known.any() else math.nan,
        "collapsed": float(longest >= 3),
    }


def interval(values: list[float], count: bool = False) -> tuple[float, float, float, int]:
    """Mean and 95% interval over seeds (Wilson for a share of seeds, t otherwise), NaNs left out."""
    mean, half, n = mean_ci(values)
    if count and n:
        return (mean, *wilson(round(mean * n), n), n)
    return mean, mean - half, mean + half, n


def summaries(frames: dict[str, Any]) -> dict[str, list[dict[str, float]]]:
    """Per arm, the :func:`summarize_run` of each finished seed of its results DataFrame."""
    return {
        arm: [{"seed": seed, **summarize_run(rows)} for seed, rows in df.groupby("seed")] for arm, df in frames.items()
    }


def table(runs: dict[str, list[dict[str, float]]]) -> str:
    """Markdown: one row per arm, each metric's mean [95% interval] (n seeds), collapses counted."""
    lines = ["| arm | seeds | " + " | ".join(METRICS) + " | collapsed |", "|---" * (len(METRICS) + 3) + "|"]
    for arm, mine in runs.items():
        if not mine:
            continue
        cells = []
        for key in METRICS:
            mean, low, high, n = interval([r[key] for r in mine], count=key == "learned")
            digits = 1 if key == "epochs_to_half" else 3 if key == "reward_per_step" else 2
            cells.append("-" if n == 0 else f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}] (n={n})")
        collapsed = int(sum(r["collapsed"] for r in mine))
        lines.append(f"| {arm} | {len(mine)} | " + " | ".join(cells) + f" | {collapsed} |")
    return "\n".join(lines)


def error_bar(values: list[float], count: bool) -> tuple[float, list[list[float]] | None] | None:
    """A bar's height and its error bar (below, above the mean; never negative) for ``values`` (:func:`interval`;
    ``count``: a share of runs, a Wilson interval); None without values, no bar where the interval is undefined."""
    mean, low, high, n = interval(values, count=count)
    if not n:
        return None
    return mean, None if math.isnan(low) else [[max(mean - low, 0.0)], [max(high - mean, 0.0)]]


def figure(frames: dict[str, Any], runs: dict[str, list[dict[str, float]]], path: Path) -> None:
    """Bars of the per-arm metrics with their intervals, and each arm's mean test goal rate per epoch."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arms = [arm for arm, mine in runs.items() if mine]
    palette = plt.get_cmap("tab10" if len(arms) <= 10 else "tab20")
    fig, axes = plt.subplots(1, len(METRICS) + 1, figsize=(3.6 * (len(METRICS) + 1), 3.6))
    for ax, key in zip(axes, METRICS, strict=False):
        for i, arm in enumerate(arms):
            bar = error_bar([r[key] for r in runs[arm]], count=key == "learned")
            if bar is not None:
                ax.bar(i, bar[0], yerr=bar[1], capsize=4, color=palette(i))
        ax.set_xticks(range(len(arms)), arms, rotation=40, ha="right")
        ax.set_title(key)
    ax = axes[-1]
    for i, arm in enumerate(arms):
        curve = frames[arm].groupby("epoch")["goal_rate"].mean()
        ax.plot(curve.index, curve.to_numpy(), color=palette(i), label=arm)
    ax.set_xlabel("epoch")
    ax.set_title("test goal rate (mean over seeds)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fixed_temperature_check(part: Part) -> str:
    """The fixed arms' temperature against the measured mean temperature of the arm it was taken from."""
    rule = part.spec["rules"].get("fixed_temperature")
    if not rule:
        return ""
    rows = part.rows[part.rows["arm"] == rule["arm"]]
    if rows.empty:
        return f"Fixed temperature {rule['value']}: arm {rule['arm']!r} has no rows to check it against."
    measured = mean_temperature(rows)
    agrees = round(measured, 4) == rule["value"]
    return (
        f"Fixed temperature {rule['value']}; arm {rule['arm']!r} measured {measured:.4f} here "
        f"({'agrees' if agrees else 'differs: the fixed arms ran at another temperature than this one'})."
    )


def report(parts: list[Part], out: Path) -> str:
    """Write ``table.md``, ``runs.json`` and ``ablation.png`` of the study's rows under ``out``; the table."""
    texts = []
    for part in parts:
        target = out / part.part if part.part else out
        frames = {arm: rows.reset_index(drop=True) for arm, rows in part.rows.groupby("arm", sort=False)}
        frames = {arm: frames[arm] for arm in part.spec["arms"] if arm in frames}
        runs = summaries(frames)
        text = "\n\n".join(t for t in (table(runs), fixed_temperature_check(part)) if t)
        target.mkdir(parents=True, exist_ok=True)
        (target / "table.md").write_text(text + "\n")
        (target / "runs.json").write_text(json.dumps(runs, indent=1))
        if frames:
            figure(frames, runs, target / "ablation.png")
        texts.append(text)
    return "\n\n".join(texts)
