"""Report of the non-regression check (``non_regression/<env>`` specs): per env, each arm's final return per seed,
its mean with a 95% t-interval and its difference to the baseline arm (``rules.baseline``) with a 95% Welch
interval; ``rules.return`` names the row field compared. Requires the ``plots`` extra (scipy).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from twodrl_bench.intervals import mean_ci, welch_ci
from twodrl_bench.reports.benchmark import task_of

Row = dict[str, Any]
Spec = dict[str, Any]


def table(env_id: str, returns: dict[str, list[float]]) -> str:
    """Markdown: per arm the returns per seed, the mean [95% t-interval] and the Welch interval of the difference
    to the first arm (the baseline)."""
    base_arm, base = next(iter(returns.items()))
    lines = [f"| {env_id} | per seed | mean [95% CI] | minus {base_arm} [95% Welch CI] |", "|---|---|---|---|"]
    for arm, values in returns.items():
        mean, half, _ = mean_ci(values)
        diff = "-"
        if arm != base_arm:
            d, h = welch_ci(values, base)
            diff = f"{d:+.1f} [{d - h:+.1f}, {d + h:+.1f}]"
        cells = ", ".join(f"{v:.1f}" for v in values)
        lines.append(f"| {arm} | {cells} | {mean:.1f} [{mean - half:.1f}, {mean + half:.1f}] | {diff} |")
    return "\n".join(lines)


def report(rows: Sequence[Row], spec: Spec | Sequence[Spec], out: str | Path) -> str:
    """One :func:`table` per spec (env) with rows, the baseline first, then the other arms in the spec's order,
    seeds in order; written to ``<out>/table.md``; the tables.

    :raises ValueError: if a row's task has no spec, or a spec's rules lack ``baseline`` or ``return``
    """
    specs = [spec] if isinstance(spec, dict) else list(spec)
    grouped: dict[str, dict[str, dict[int, float]]] = {task_of(s): {} for s in specs}
    for s in specs:
        missing = [key for key in ("baseline", "return") if key not in s["rules"]]
        if missing:
            raise ValueError(f"{s['name']}: rules lack {missing}")
    for s in specs:
        key = s["rules"]["return"]
        for row in rows:
            if row["task"] not in grouped:
                raise ValueError(f"rows: task {row['task']!r} is none of the specs' tasks {sorted(grouped)}")
            if row["task"] == task_of(s):
                grouped[row["task"]].setdefault(row["arm"], {})[int(row["seed"])] = float(row[key])
    tables = []
    for s in specs:
        by_arm = grouped[task_of(s)]
        order = [s["rules"]["baseline"], *(a for a in s["arms"] if a != s["rules"]["baseline"])]
        returns = {arm: [by_arm[arm][seed] for seed in sorted(by_arm[arm])] for arm in order if arm in by_arm}
        if returns:
            tables.append(table(task_of(s), returns))
    text = "\n\n".join(tables)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    return text
