"""Report of the public-task benchmark (``benchmark/<Task>`` specs, docs/public_tasks.md): one table over the tasks,
each 2D-RL arm against its stock arm with the pre-registered verdict, and a learning-curve figure per task.

Each spec's ``rules`` hold what the report reads: ``compare`` (2D-RL arm -> stock arm), ``min_seeds`` (fewer
seeds of either arm: no verdict), ``return`` and ``events`` (the row fields the rule compares; ``events: null``
on a task without punishment events), ``paths`` (lengths of the event-free deterministic paths whose share of
seeds is counted) and ``published`` (rl-zoo3's published figure per stock algo, context only).
Requires the ``plots`` extra (scipy for the intervals, matplotlib for the figures).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_bench.intervals import mean_ci, welch_ci, wilson

Row = dict[str, Any]
Spec = dict[str, Any]
INTS = ("seed", "n_timesteps", "train_episodes")
FLOATS = (
    "final_return",
    "final_return_std",
    "final_length",
    "final_events",
    "final_event_share",
    "train_return",
    "train_events_per_episode",
    "train_event_share",
    "wall_s",
)


def typed(row: Row) -> Row:
    """``row`` with its numbers as numbers and its ``curve`` as a list (a row read back from CSV holds text)."""
    out = {}
    for key, value in row.items():
        if key in INTS:
            value = int(value)
        elif key == "curve":
            value = json.loads(value) if isinstance(value, str) else value
        elif key in FLOATS:
            value = float(value)
        out[key] = value
    return out


def task_of(spec: Spec) -> str:
    """The ``task`` label of the rows ``spec`` makes (:mod:`twodrl_bench.timesteps`)."""
    return spec["protocol"].get("task") or spec["env"]


def mean_cell(values: Sequence[float], digits: int = 1) -> str:
    """``mean [low, high] (n=N)``: the mean of ``values`` with its 95% Student t interval; ``-`` for none."""
    mean, half, n = mean_ci(values)
    if n == 0:
        return "-"
    if not math.isfinite(half) or half == 0:
        return f"{mean:.{digits}f} (n={n})"
    return f"{mean:.{digits}f} [{mean - half:.{digits}f}, {mean + half:.{digits}f}] (n={n})"


def welch_cell(a: Sequence[float], b: Sequence[float], digits: int = 1) -> str:
    """``+d [low, high]``: the difference of the means of ``a`` and ``b`` with its 95% Welch interval."""
    if len(a) < 2 or len(b) < 2:
        return "-"
    d, h = welch_ci(a, b)
    if not math.isfinite(h):
        h = 0.0
    return f"{d:+.{digits}f} [{d - h:+.{digits}f}, {d + h:+.{digits}f}]"


def verdict(
    ret_2d: Sequence[float],
    ret_st: Sequence[float],
    ev_2d: Sequence[float],
    ev_st: Sequence[float],
    min_seeds: int,
) -> str:
    """The pre-registered rule (docs/public_tasks.md): 95% Welch intervals of 2D - stock on the return and the events.

    Helps if the return's interval is wholly above 0, or the events' wholly below 0 and the return's not wholly
    below 0; hurts if the return's is wholly below 0 or the events' wholly above 0; both: trade-off. Events are
    left out where they are empty (a task without punishment events).
    """
    if min(len(ret_2d), len(ret_st)) < min_seeds:
        return f"no verdict (< {min_seeds} seeds)"

    def interval(a: Sequence[float], b: Sequence[float]) -> tuple[float, float]:
        d, h = welch_ci(a, b)
        return (d, d) if not math.isfinite(h) else (d - h, d + h)

    ret_lo, ret_hi = interval(ret_2d, ret_st)
    ev_lo, ev_hi = interval(ev_2d, ev_st) if ev_2d and all(map(math.isfinite, [*ev_2d, *ev_st])) else (0.0, 0.0)
    helps = ret_lo > 0 or (ev_hi < 0 and not ret_hi < 0)
    hurts = ret_hi < 0 or ev_lo > 0
    if helps and hurts:
        return "trade-off"
    return "helps" if helps else "hurts" if hurts else "no difference shown"


def _by_arm(rows: Sequence[Row]) -> dict[str, dict[int, Row]]:
    by_arm: dict[str, dict[int, Row]] = {}
    for row in rows:
        by_arm.setdefault(row["arm"], {})[row["seed"]] = row
    return by_arm


def comparison_lines(spec: Spec, rows: Sequence[Row]) -> list[str]:
    """Per 2D-RL arm of ``spec.rules.compare`` with rows, against its stock arm over the seeds both have: the means
    with 95% t-intervals, the differences with 95% Welch intervals, the verdict (markdown table lines)."""
    rules, task = spec["rules"], task_of(spec)
    by_arm = _by_arm(rows)
    ret_key, ev_key = rules["return"], rules.get("events")
    lines = []
    for arm in sorted(by_arm):
        stock = rules["compare"].get(arm)
        if stock is None or stock not in by_arm:
            continue
        seeds = sorted(by_arm[arm].keys() & by_arm[stock].keys())
        two = [by_arm[arm][s] for s in seeds]
        base = [by_arm[stock][s] for s in seeds]
        ret_2d, ret_st = [r[ret_key] for r in two], [r[ret_key] for r in base]
        ev_2d = [r[ev_key] for r in two] if ev_key else []
        ev_st = [r[ev_key] for r in base] if ev_key else []
        events = (
            f"{mean_cell(ev_st, 3)} | {mean_cell(ev_2d, 3)} | {welch_cell(ev_2d, ev_st, 3)}" if ev_key else "- | - | -"
        )
        budget = f"{base[0]['n_timesteps']:,}" if base else "-"
        lines.append(
            f"| {task} | {budget} | {stock} | {mean_cell(ret_st)} | {arm} | {mean_cell(ret_2d)} "
            f"| {welch_cell(ret_2d, ret_st)} "
            f"| {events} | {verdict(ret_2d, ret_st, ev_2d, ev_st, rules['min_seeds'])} "
            f"| {rules.get('published', {}).get(stock, '-')} |"
        )
    return lines


def path_table(paths: Sequence[int], rows: Sequence[Row]) -> str:
    """Per arm, the share of seeds whose final deterministic episodes take each path (event-free, that length)."""
    names = [f"{n}-step path" for n in paths]
    lines = [f"| arm | {' | '.join(names)} | other (timeout, fall, mixed) |", "|" + "---|" * (len(names) + 2)]
    for arm, seeds in sorted(_by_arm(rows).items()):
        arm_rows = list(seeds.values())
        counts = [sum(r["final_length"] == n and r["final_events"] == 0 for r in arm_rows) for n in paths]
        cells = [*counts, len(arm_rows) - sum(counts)]
        text = [f"{k}/{len(arm_rows)} [{lo:.2f}, {hi:.2f}]" for k in cells for lo, hi in [wilson(k, len(arm_rows))]]
        lines.append(f"| {arm} | {' | '.join(text)} |")
    return "\n".join(lines)


def figure(spec: Spec, rows: Sequence[Row], path: Path) -> None:
    """Learning curves: per arm the mean training return per bin over seeds, with its 95% t-interval."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for arm in sorted({r["arm"] for r in rows}):
        curves = np.array([r["curve"] for r in rows if r["arm"] == arm])  # seeds x bins x 3
        stats = [mean_ci(curves[:, b, 1]) for b in range(curves.shape[1])]
        x = curves[0, :, 0]
        mean = np.array([m for m, _, _ in stats])
        half = np.nan_to_num(np.array([h for _, h, _ in stats]))
        ax.plot(x, mean, label=f"{arm} (n={len(curves)})")
        ax.fill_between(x, mean - half, mean + half, alpha=0.2)
    ax.set_xlabel("timesteps")
    ax.set_ylabel("training episode return")
    ax.set_title(f"{task_of(spec)} ({spec['env']})")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def report(rows: Sequence[Row], spec: Spec | Sequence[Spec], out: str | Path, figures: bool = True) -> str:
    """The benchmark's table over the tasks of ``spec`` (one spec or the study's specs, one per task), written to
    ``<out>/table.md`` with a figure ``<out>/<task>_curve.png`` per task (unless ``figures`` is false); the table.

    :raises ValueError: if a row's task has no spec, or a spec's rules lack a key the report reads
    """
    specs = [spec] if isinstance(spec, dict) else list(spec)
    by_task = {task_of(s): s for s in specs}
    for s in specs:
        missing = [key for key in ("compare", "min_seeds", "return", "events") if key not in s["rules"]]
        if missing:
            raise ValueError(f"{s['name']}: rules lack {missing}")
    grouped: dict[str, list[Row]] = {task: [] for task in by_task}
    for row in map(typed, rows):
        if row["task"] not in grouped:
            raise ValueError(f"rows: task {row['task']!r} is none of the specs' tasks {sorted(by_task)}")
        grouped[row["task"]].append(row)
    head = "| task | budget | stock arm | return | 2D-RL arm | return | 2D - stock [95% Welch] |"
    head += " training events/episode, stock | 2D | 2D - stock | verdict | rl-zoo3 published (v2 where marked) |"
    lines = [head, "|" + "---|" * 12]
    for task, task_rows in grouped.items():
        lines += comparison_lines(by_task[task], task_rows)
    for task, task_rows in grouped.items():
        paths = by_task[task]["rules"].get("paths")
        if paths and task_rows:
            lines += ["", f"{task}: final deterministic path per seed", "", path_table(paths, task_rows)]
    text = "\n".join(lines)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    if figures:
        for task, task_rows in grouped.items():
            if task_rows:
                figure(by_task[task], task_rows, out / f"{task}_curve.png")
    return text
