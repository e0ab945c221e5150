"""Report of the self-tuning entropy study (``auto_entropy/<task>`` specs; ``results/auto_entropy/preregistration.md``):
per task, each arm over seeds, the registered verdict of "the interest is a tuning-free exploration setting on
task X" and the descriptive comparisons. A timesteps task's rows are one per run; a task at the paper's epochs
(the office) is first read per run (:func:`epoch_runs`).

Each spec's ``rules`` hold what the verdict reads: ``claim`` (the 2D-RL arm at ``ent_coef`` 0), ``against`` (the
automatic stock arms; the *reference* is the one with the higher mean return, the first on a tie), ``zero`` (the
stock arm at 0), ``fixed`` (the stock arm at its best fixed coefficient), ``pairs`` (2D arm -> stock arm, the
descriptive differences), ``return``/``return_margin``, ``events``/``events_margin`` (row fields and margins) and
``min_seeds``. The differences are (claim - each automatic arm), (each other automatic arm - fixed), the pairs and
(claim - fixed), each once. The claim holds if the Welch interval of (claim - reference) has its lower bound above
``-return_margin`` on the return and its upper bound below ``events_margin`` on the events; it is informative only
if zero is worse than the reference (return interval wholly below 0, or events wholly above 0). With ``learned``
(``{metric, at_least}``: a run learned if its last epoch's ``metric`` reaches ``at_least``) the claim also needs
as many learned seeds as the reference or overlapping Wilson intervals, and zero learning on fewer seeds with
non-overlapping ones makes the task informative; with ``extend`` the report says for which pairs the registered
extension fires (:func:`extension`). Where the rows
carry it, the automatic arms' coefficient course follows (:func:`course_table`). Each part (spec) is read from its
own rows, so two parts on one env (the office's A2C and PPO specs, an extension) stay apart. Requires the
``plots`` extra (scipy).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sb3_twodrl.callbacks import SUCCESS_THRESHOLD
from twodrl_bench.intervals import welch_ci, wilson
from twodrl_bench.reports import Part
from twodrl_bench.reports.benchmark import mean_cell, welch_cell
from twodrl_bench.reports.factorial import run_metrics

Row = dict[str, Any]
COURSE_AT = (10, 50, 100)
"""Percent of training at which the coefficient's course is reported (the pre-registration's points)."""
DESCRIPTIVE = ("final_length", "shortcut_share", "detour_share", "epochs_to_half")
"""Registered descriptive columns, where the rows have them: the final evaluation's episode length (CliffWalking's
path: 13, 15 or 17 steps, 100 if it never reaches the goal) and the office's final route shares and first epoch at
a goal rate >= 0.5 (its mean over the seeds that reached it). See :func:`_descriptive`."""
MAX_PATHS = 5
"""A descriptive column with at most this many distinct values over a task's runs is shown as counts."""
LEARNED = {"metric": "goal_rate", "at_least": SUCCESS_THRESHOLD}
"""The learned rule an epoch task must register: the factorial's (:func:`.factorial.run_metrics`)."""
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
    reference = reference_of(values, rules)
    claim, ref = values[rules["claim"]], values[reference]
    ret_lo, _ = _interval(claim["return"], ref["return"])
    _, ev_hi = _interval(claim["events"], ref["events"])
    holds = ret_lo > -rules["return_margin"] and ev_hi < rules["events_margin"]
    if rules.get("learned"):
        holds = holds and not _fewer_learned(claim["learned"], ref["learned"])
    outcome = "holds" if holds else "fails"
    if holds and ret_lo > 0:
        outcome += "; the interest beats the automatic coefficient"
    zero = values[rules["zero"]]
    zero_ret_hi = _interval(zero["return"], ref["return"])[1]
    zero_ev_lo = _interval(zero["events"], ref["events"])[0]
    zero_learns_fewer = bool(rules.get("learned")) and _fewer_learned(zero["learned"], ref["learned"])
    if not (zero_ret_hi < 0 or zero_ev_lo > 0 or zero_learns_fewer):  # the bonus does not matter to the stock one
        return (
            f"reference {reference}; untested: the stock algorithm does as well without a bonus as with the "
            f"automatic one (the claim's conditions: it {outcome})"
        )
    return f"reference {reference}; the claim {outcome}"


def _fewer_learned(a: Sequence[float], b: Sequence[float]) -> bool:
    """``a`` learned on fewer seeds than ``b`` and their Wilson intervals do not overlap."""
    (a_lo, a_hi), (b_lo, b_hi) = wilson(int(sum(a)), len(a)), wilson(int(sum(b)), len(b))
    return sum(a) < sum(b) and (a_hi < b_lo or b_hi < a_lo)


def reference_of(values: dict[str, dict[str, list[float]]], rules: dict[str, Any]) -> str:
    """The arm of ``against`` with the higher mean return (the first on a tie)."""
    return max(rules["against"], key=lambda arm: sum(values[arm]["return"]) / len(values[arm]["return"]))


def extension(values: dict[str, dict[str, list[float]]], rules: dict[str, Any]) -> str:
    """The registered extension's sentence: the pairs of ``extend.pairs`` (``claim``, ``zero``, ``reference``
    or arm names) whose return Welch interval holds 0 while either arm still moves (the mean over seeds of the
    change between ``extend.windows``' two windows exceeds ``move_margin`` in absolute value)."""
    ext = rules["extend"]
    names = {"claim": rules["claim"], "zero": rules["zero"], "reference": reference_of(values, rules)}
    fires = []
    for pair in ext["pairs"]:
        a, b = (names.get(arm, arm) for arm in pair)
        lo, hi = _interval(values[a]["return"], values[b]["return"])
        moves = [abs(sum(values[arm]["move"]) / len(values[arm]["move"])) > ext["move_margin"] for arm in (a, b)]
        if lo <= 0 <= hi and any(moves):
            fires.append(f"({a}, {b})")
    epochs = ext["epochs"]
    if not fires:
        return f"Extension to {epochs} epochs: fires for no pair; the verdict above is final."
    return f"Extension to {epochs} epochs: fires for {', '.join(fires)}; the rule is read on their {epochs}-epoch rows."


def epoch_runs(frame: Any, rules: dict[str, Any]) -> list[Row]:
    """The paper's epoch rows (``frame``, one per epoch, as :func:`~twodrl_bench.folders.collect` reads them) read
    per (arm, seed) with the factorial's :func:`~twodrl_bench.reports.factorial.run_metrics` (the last 10% of epochs;
    learned: the last epoch's goal rate >= :data:`~sb3_twodrl.callbacks.SUCCESS_THRESHOLD`, which
    ``rules["learned"]`` must register), plus ``move`` (``rules["extend"]``'s late window minus its early one, on
    reward per step) and, for a learned coefficient, ``ent_coef_course`` (``ent_coef`` and ``entropy_fraction`` at
    each tenth of the epochs)."""
    if rules["learned"] != LEARNED:
        raise ValueError(f"rules['learned'] must be the factorial's {LEARNED}, got {rules['learned']}")
    out = []
    for (arm, seed), epochs in frame.groupby(["arm", "seed"], sort=True):
        epochs = epochs.sort_values("epoch").reset_index(drop=True)
        metrics = run_metrics(epochs)
        run: Row = {"arm": arm, "seed": int(seed), "epochs": len(epochs)}
        run |= {key: metrics[key] for key in ("reward_per_step", "collision_rate", "learned", "epochs_to_half")}
        run |= {"shortcut_share": metrics["final_shortcut_share"], "detour_share": metrics["final_detour_share"]}
        if "extend" in rules:
            (a0, a1), (b0, b1) = rules["extend"]["windows"]
            late = epochs.loc[epochs["epoch"].between(b0, b1), "reward_per_step"].mean()
            run["move"] = float(late - epochs.loc[epochs["epoch"].between(a0, a1), "reward_per_step"].mean())
        if "ent_coef" in epochs and epochs["ent_coef"].notna().any():
            points = epochs.iloc[[max(1, round(d * len(epochs) / 10)) - 1 for d in range(1, 11)]]
            course = points[["env_steps", "ent_coef", "entropy_fraction"]].to_numpy(dtype=float).tolist()
            run["ent_coef_course"] = json.dumps([[int(steps), alpha, share] for steps, alpha, share in course])
        out.append(run)
    return out


def _descriptive(values: dict[str, dict[str, list[float]]], arm: str, key: str) -> str:
    """Mean over seeds with its interval; for a task whose runs all end on one of :data:`MAX_PATHS` values
    (CliffWalking's deterministic paths), the count of seeds per value."""
    everywhere = {v for arm_values in values.values() for v in arm_values.get(key, [])}
    mine = [v for v in values[arm].get(key, []) if math.isfinite(v)]
    if len(everywhere) > MAX_PATHS:
        return mean_cell(mine, 2)
    return ", ".join(f"{v:g}: {mine.count(v)}" for v in sorted(set(mine)))


def task_report(part: Part) -> str:
    """Markdown for one part: arms over seeds, the verdict, the descriptive differences."""
    spec = part.spec
    rules = spec["rules"]
    missing = [key for key in RULE_KEYS if key not in rules]
    if missing:
        raise ValueError(f"rules of {spec['name']} lack {missing}")
    if "epochs" in spec["protocol"]:
        rows = epoch_runs(part.rows, rules)
    else:
        rows = part.rows.to_dict("records")
    values: dict[str, dict[str, list[float]]] = {}
    for row in sorted(rows, key=lambda r: (r["arm"], r["seed"])):
        arm = values.setdefault(row["arm"], {"return": [], "events": [], "learned": [], "move": []})
        arm["return"].append(float(row[rules["return"]]))
        arm["events"].append(float(row[rules["events"]]))
        for key in ("learned", "move", *DESCRIPTIVE):
            if key in row:
                arm.setdefault(key, []).append(float(row[key]))
    digits = 4 if "epochs" in spec["protocol"] else 2
    learned = "learned" in rules
    shown = [key for key in DESCRIPTIVE if any(key in arm for arm in values.values())]
    head = [rules["return"], rules["events"], *(["learned"] if learned else []), *shown]
    lines = [f"### {part.part or spec['name']}", "", f"| arm | {' | '.join(head)} |", "|---|" + "---|" * len(head)]
    for arm in spec["arms"]:
        if arm in values:
            cells = [mean_cell(values[arm]["return"], digits), mean_cell(values[arm]["events"], 3)]
            if learned:
                k, n = int(sum(values[arm]["learned"])), len(values[arm]["learned"])
                lo, hi = wilson(k, n)
                cells.append(f"{k}/{n} [{lo:.2f}, {hi:.2f}]")
            cells += [_descriptive(values, arm, key) for key in shown]
            lines.append(f"| {arm} | {' | '.join(cells)} |")
    reading = verdict(values, rules)
    lines += ["", f"Verdict: {reading}."]
    if "extend" in rules and not reading.startswith("no verdict"):
        lines += ["", extension(values, rules)]
    lines += ["", "| difference | return | events |", "|---|---|---|"]
    comparisons = [(rules["claim"], arm) for arm in rules["against"]] + [
        (arm, rules["fixed"]) for arm in rules["against"] if arm != rules["fixed"]
    ]
    comparisons += [(a, b) for a, b in rules["pairs"].items()]
    comparisons.append((rules["claim"], rules["fixed"]))
    for a, b in dict.fromkeys(comparisons):
        if a in values and b in values:
            ret = welch_cell(values[a]["return"], values[b]["return"], digits)
            ev = welch_cell(values[a]["events"], values[b]["events"], 3)
            lines.append(f"| {a} - {b} | {ret} | {ev} |")
    if lines[-1] == "|---|---|---|":  # no pair with rows on both sides yet
        lines = lines[:-3]
    return "\n".join(lines + course_table(rows))


def course_table(rows: Sequence[Row]) -> list[str]:
    """The automatic arms' coefficient over seeds at 10%, 50% and 100% of training (:data:`COURSE_AT`), from
    the rows' ``ent_coef_course`` (:mod:`twodrl_bench.algorithms.auto_entropy`); no lines if no row has one."""
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
            cells += [mean_cell([point[1] for point in points], 3), mean_cell([point[2] for point in points], 3)]
        lines.append(f"| {arm} | {' | '.join(cells)} |")
    return lines


def report(parts: list[Part], out: Path) -> str:
    """One :func:`task_report` per part with rows, written to ``<out>/table.md``; the text."""
    text = "\n\n".join(task_report(part) for part in parts if len(part.rows))
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    return text
