"""Report of the self-tuning entropy study (``auto_entropy/<task>`` timesteps specs;
``results/auto_entropy/preregistration.md``): per task, each arm over seeds, the registered verdict of "the
interest is a tuning-free exploration setting on task X" and the descriptive comparisons.

Each spec's ``rules`` hold what the verdict reads: ``claim`` (the 2D-RL arm at ``ent_coef`` 0), ``against`` (the
automatic stock arms; the *reference* is the one with the higher mean return, the first on a tie), ``zero`` (the
stock arm at 0), ``fixed`` (the stock arm at its best fixed coefficient), ``pairs`` (2D arm -> stock arm, the
descriptive differences), ``return``/``return_margin``, ``events``/``events_margin`` (row fields and margins) and
``min_seeds``. The claim holds if the Welch interval of (claim - reference) has its lower bound above
``-return_margin`` on the return and its upper bound below ``events_margin`` on the events; it is informative only
if zero is worse than the reference (return interval wholly below 0, or events wholly above 0). Where the rows
carry it, the automatic arms' coefficient course follows (:func:`course_table`). Requires the ``plots`` extra
(scipy).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from twodrl_bench.intervals import welch_ci
from twodrl_bench.reports.benchmark import _cell, _diff, task_of, typed

Row = dict[str, Any]
Spec = dict[str, Any]
COURSE_AT = (10, 50, 100)
"""Percent of training at which the coefficient's course is reported (the pre-registration's points)."""
RULE_KEYS = ("claim", "against", "zero", "fixed", "pairs", "return", "return_margin", "events", "events_margin")


def _interval(a: Sequence[float], b: Sequence[float]) -> tuple[float, float]:
    d, h = welch_ci(a, b)
    return (d, d) if not math.isfinite(h) else (d - h, d + h)


def verdict(values: dict[str, dict[str, list[float]]], rules: dict[str, Any]) -> str:
    """The registered verdict on one task from ``values[arm][metric]`` (metric ``return`` or ``events``)."""
    arms = [rules["claim"], rules["zero"], *rules["against"]]
    short = [arm for arm in arms if len(values.get(arm, {}).get("return", [])) < rules.get("min_seeds", 10)]
    if short:
        return f"no verdict: fewer than {rules.get('min_seeds', 10)} seeds for {', '.join(short)}"
    reference = max(rules["against"], key=lambda arm: sum(values[arm]["return"]) / len(values[arm]["return"]))
    claim, zero, ref = values[rules["claim"]], values[rules["zero"]], values[reference]
    ret_lo, _ = _interval(claim["return"], ref["return"])
    _, ev_hi = _interval(claim["events"], ref["events"])
    zero_ret_hi = _interval(zero["return"], ref["return"])[1]
    zero_ev_lo = _interval(zero["events"], ref["events"])[0]
    holds = ret_lo > -rules["return_margin"] and ev_hi < rules["events_margin"]
    outcome = "holds" if holds else "fails"
    if holds and ret_lo > 0:
        outcome += "; the interest beats the automatic coefficient"
    if not (zero_ret_hi < 0 or zero_ev_lo > 0):  # the bonus does not matter to the stock algorithm here
        return (
            f"reference {reference}; untested: the stock algorithm does as well without a bonus as with the "
            f"automatic one (the claim's conditions: it {outcome})"
        )
    return f"reference {reference}; the claim {outcome}"


def task_report(spec: Spec, rows: Sequence[Row]) -> str:
    """Markdown for one task: arms over seeds, the verdict, the descriptive differences."""
    rules = spec["rules"]
    missing = [key for key in RULE_KEYS if key not in rules]
    if missing:
        raise ValueError(f"rules of {spec['name']} lack {missing}")
    values: dict[str, dict[str, list[float]]] = {}
    for row in sorted(rows, key=lambda r: (r["arm"], r["seed"])):
        arm = values.setdefault(row["arm"], {"return": [], "events": []})
        arm["return"].append(float(row[rules["return"]]))
        arm["events"].append(float(row[rules["events"]]))
    lines = [
        f"### {task_of(spec)}",
        "",
        f"| arm | {rules['return']} | {rules['events']} |",
        "|---|---|---|",
    ]
    for arm in spec["arms"]:
        if arm in values:
            lines.append(f"| {arm} | {_cell(values[arm]['return'], 2)} | {_cell(values[arm]['events'], 3)} |")
    lines += ["", f"Verdict: {verdict(values, rules)}.", "", "| difference | return | events |", "|---|---|---|"]
    comparisons = [(rules["claim"], arm) for arm in rules["against"]] + [
        (arm, rules["fixed"]) for arm in rules["against"] if arm != rules["fixed"]
    ]
    comparisons += [(a, b) for a, b in rules["pairs"].items()]
    for a, b in comparisons:
        if a in values and b in values:
            ret = _diff(values[a]["return"], values[b]["return"], 2)
            ev = _diff(values[a]["events"], values[b]["events"], 3)
            lines.append(f"| {a} - {b} | {ret} | {ev} |")
    return "\n".join(lines + course_table(rows))


def course_table(rows: Sequence[Row]) -> list[str]:
    """The automatic arms' coefficient over seeds at 10%, 50% and 100% of training (:data:`COURSE_AT`), from
    the rows' ``ent_coef_course`` (:mod:`twodrl_bench.auto_entropy`); no lines if no row has one."""
    courses: dict[str, list[list[list[float]]]] = {}
    for row in sorted(rows, key=lambda r: (r["arm"], r["seed"])):
        text = row.get("ent_coef_course")
        if isinstance(text, str) and text:
            courses.setdefault(row["arm"], []).append(json.loads(text))
    if not courses:
        return []
    head = " | ".join(f"alpha at {p}% | entropy / max at {p}%" for p in COURSE_AT)
    lines = ["", f"| automatic arm | {head} |", "|---|" + "---|" * 2 * len(COURSE_AT)]
    for arm, runs in courses.items():
        cells = []
        for p in COURSE_AT:
            points = [run[p // 10 - 1] for run in runs if run[p // 10 - 1] is not None]
            cells += [_cell([point[1] for point in points], 3), _cell([point[2] for point in points], 3)]
        lines.append(f"| {arm} | {' | '.join(cells)} |")
    return lines


def report(rows: Sequence[Row], spec: Spec | Sequence[Spec], out: str | Path) -> str:
    """One :func:`task_report` per spec with rows, written to ``<out>/table.md``; the text."""
    specs = [spec] if isinstance(spec, dict) else list(spec)
    rows = [typed(row) for row in rows]
    parts = []
    for one in specs:
        task = task_of(one)
        mine = [row for row in rows if row.get("task", task) == task]
        if mine:
            parts.append(task_report(one, mine))
    text = "\n\n".join(parts)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    return text
