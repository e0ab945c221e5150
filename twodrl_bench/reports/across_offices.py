"""2D-RL across offices (``results/across_offices/preregistration.md``): the registered rules applied to the rows.

Parts ``S`` and ``M``: TwoDimA2C and A2C on generated offices, one row per (arm, map), the training seed the map
seed, so the arms pair by map. Rules R1-R4 compare them over the pairs of both parts (paired 95% Student
t-intervals of claim minus reference): collisions per training episode (R1, guarded by the maps learned), maps
learned (R2), steps to the first goal from the start (R3, log10 ratio over the maps where both reached one) and
reward per step at the end (R4). Parts ``transfer_database`` and ``transfer_simulator``: each arm trained on the
recorded database and on the ideal simulator, tested on the stand-in robot; rule T1 compares the two per arm.
The report reads the rows and the specs' ``rules`` only; it writes ``table.md``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_bench.intervals import mean_ci, wilson
from twodrl_bench.protocol import PAPER_TRIALS
from twodrl_bench.reports import Part

Pairs = dict[int, tuple[dict[str, Any], dict[str, Any]]]


def _rows(part: Part, arm: str) -> dict[int, dict[str, Any]]:
    """``part``'s rows of ``arm`` by seed (the map seed)."""
    if part.rows.empty:
        return {}
    mine = part.rows[part.rows["arm"] == arm]
    return {int(row["seed"]): row for row in mine.to_dict("records")}


def pairs(parts: list[Part], claim: str, reference: str) -> Pairs:
    """``(part, seed) -> (claim's row, reference's row)`` over the maps both arms finished, keyed by an index."""
    out: Pairs = {}
    for part in parts:
        a, b = _rows(part, claim), _rows(part, reference)
        for seed in sorted(set(a) & set(b)):
            out[len(out)] = (a[seed], b[seed])
    return out


def interval(values: list[float], digits: int = 3, share: bool = False) -> tuple[str, float, float]:
    """``mean [low, high]`` with its 95% t-interval, and the bounds (NaN with fewer than 2 values); a ``share``'s
    interval is clipped to [0, 1]."""
    mean, half, n = mean_ci(values)
    if n == 0:
        return "-", math.nan, math.nan
    if n == 1 or not np.isfinite(half):
        return f"{mean:.{digits}f} (n = 1)", math.nan, math.nan
    low, high = (max(mean - half, 0.0), min(mean + half, 1.0)) if share else (mean - half, mean + half)
    return f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]", low, high


def _learned(row: dict[str, Any], at: float) -> float:
    return float(row["final_success_share"] >= at)


def _direction(low: float, high: float, less: str, more: str) -> str:
    if high < 0:
        return less
    if low > 0:
        return more
    return "no difference shown"


def comparison(found: Pairs, rules: dict[str, Any]) -> tuple[list[str], dict[str, str]]:
    """The R1-R4 table's lines and each rule's verdict, over the pairs ``found``."""
    claim, reference, at = rules["claim"], rules["reference"], rules["learned_at"]
    key, margin = rules["collisions"], rules["reward_margin"]
    a = [p[0] for p in found.values()]
    b = [p[1] for p in found.values()]
    n = len(found)
    lines = [
        f"| measure | {claim} | {reference} | paired difference ({claim} - {reference}), 95% interval | verdict |",
        "| --- | --- | --- | --- | --- |",
    ]
    verdicts: dict[str, str] = {}
    collisions = [float(x[key]) - float(y[key]) for x, y in zip(a, b, strict=True)]
    learned = [_learned(x, at) - _learned(y, at) for x, y in zip(a, b, strict=True)]
    text_c, low_c, high_c = interval(collisions)
    text_l, low_l, high_l = interval(learned, 2)
    if high_c < 0:
        guarded = low_l > rules["learned_guard"]
        verdicts["R1"] = (
            f"holds: {claim} collides less"
            if guarded
            else "not shown: fewer collisions, but the learned interval reaches below the guard"
        )
    else:
        verdicts["R1"] = f"{claim} collides more" if low_c > 0 else "no difference shown"
    lines.append(
        f"| R1: collisions per training episode | {interval([float(x[key]) for x in a])[0]} | "
        f"{interval([float(y[key]) for y in b])[0]} | {text_c} | {verdicts['R1']} |"
    )
    counts = []
    for rows in (a, b):
        k = int(sum(_learned(r, at) for r in rows))
        low, high = wilson(k, n)
        counts.append(f"{k}/{n} [{low:.2f}, {high:.2f}]")
    verdicts["R2"] = _direction(low_l, high_l, "fewer learned", "more learned")
    lines.append(f"| R2: maps learned (goal share >= {at}) | {counts[0]} | {counts[1]} | {text_l} | {verdicts['R2']} |")
    both = [(float(x["first_goal_at"]), float(y["first_goal_at"])) for x, y in zip(a, b, strict=True)]
    reached = [(x, y) for x, y in both if np.isfinite(x) and np.isfinite(y)]
    text_s, low_s, high_s = interval([math.log10(x / y) for x, y in reached], 2)
    verdicts["R3"] = _direction(low_s, high_s, f"{claim} faster", f"{claim} slower")
    medians = []
    for i in (0, 1):
        steps = [p[i] for p in both if np.isfinite(p[i])]
        none = len(both) - len(steps)
        medians.append(f"{np.median(steps):,.0f} (none: {none})" if steps else f"- (none: {none})")
    lines.append(
        f"| R3: steps to the first goal, median (maps with none) | {medians[0]} | {medians[1]} | "
        f"log10 ratio {text_s} over {len(reached)} maps | {verdicts['R3']} |"
    )
    reward = [float(x["final_reward_per_step"]) - float(y["final_reward_per_step"]) for x, y in zip(a, b, strict=True)]
    text_r, low_r, high_r = interval(reward, 4)
    if -margin <= low_r and high_r <= margin:
        verdicts["R4"] = f"equal within {margin}"
    else:
        verdicts["R4"] = _direction(low_r, high_r, "lower", "higher").replace("no difference shown", "undecided")
    lines.append(
        f"| R4: reward per step at the end | {interval([float(x['final_reward_per_step']) for x in a], 4)[0]} | "
        f"{interval([float(y['final_reward_per_step']) for y in b], 4)[0]} | {text_r} | {verdicts['R4']} |"
    )
    return lines, verdicts


def every_map(parts: list[Part], claim: str, reference: str, at: float, key: str) -> list[str]:
    """One line per map: budget, and per arm collisions per training episode, final goal share, first goal."""
    lines = [
        f"| map | budget | collisions {claim} | collisions {reference} | goal share {claim} | goal share {reference} "
        f"| first goal {claim} | first goal {reference} |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for part in parts:
        for x, y in pairs([part], claim, reference).values():
            first = [f"{v:,.0f}" if np.isfinite(v) else "none" for v in (x["first_goal_at"], y["first_goal_at"])]
            lines.append(
                f"| {part.spec['env_kwargs']['map'].replace('{seed}', str(x['seed']))} | {int(x['n_timesteps']):,} | "
                f"{float(x[key]):.3f} | {float(y[key]):.3f} | {float(x['final_success_share']):.2f} | "
                f"{float(y['final_success_share']):.2f} | {first[0]} | {first[1]} |"
            )
    return lines


def transfer(parts: dict[str, Part], rules: dict[str, Any]) -> tuple[list[str], list[str]]:
    """The transfer table (per arm and training env, the stand-in robot's goal share) and rule T1's verdicts."""
    database, simulator = parts.get(rules["database"]), parts.get(rules["simulator"])
    if database is None or simulator is None:
        return ["(the transfer parts have not both run)"], []
    paper = rules["paper_successes"]
    trials = database.spec["protocol"]["transfer"]["trials"]
    lines = [
        f"| arm | trained on | maps | goal share on the stand-in robot, mean over maps (t-interval within [0, 1]) | "
        f"maps with >= {paper} of the "
        f"first {PAPER_TRIALS} | maps with 0 of {trials} | goal share in its training env |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    verdicts: list[str] = []
    by_map: dict[int, dict[tuple[str, str], str]] = {}
    for arm in database.spec["arms"]:
        shares = {}
        for label, part in (("database", database), ("simulator", simulator)):
            rows = _rows(part, arm)
            share = {s: float(r["transfer_success"]) / trials for s, r in rows.items()}
            shares[label] = share
            mean = interval(list(share.values()), 2, True)[0]
            lines.append(
                f"| {arm} | {label} ({part.spec['env']}) | {len(rows)} | {mean} | "
                f"{sum(int(r['transfer_paper_successes']) >= paper for r in rows.values())} | "
                f"{sum(int(r['transfer_success']) == 0 for r in rows.values())} | "
                f"{interval([float(r['final_success_share']) for r in rows.values()], 2, True)[0]} |"
            )
            for seed, r in rows.items():
                by_map.setdefault(seed, {})[(arm, label)] = f"{int(r['transfer_success'])}"
        common = sorted(set(shares["database"]) & set(shares["simulator"]))
        diffs = [shares["database"][s] - shares["simulator"][s] for s in common]
        text, low, high = interval(diffs, 2)
        verdict = _direction(low, high, "reversed: the simulator's policies transfer better", "holds")
        verdicts.append(
            f"- T1, {arm}: database minus simulator goal share, paired over {len(common)} maps: {text}: {verdict}."
        )
    columns = [(arm, label) for arm in database.spec["arms"] for label in ("database", "simulator")]
    lines += ["", f"Goals in the {trials} trials on the stand-in robot, every map:", ""]
    lines += [
        "| map | " + " | ".join(f"{arm}, {label}" for arm, label in columns) + " |",
        "|" + " --- |" * (1 + len(columns)),
    ]
    place = database.spec["env_kwargs"]["map"]
    for seed in sorted(by_map):
        cells = [by_map[seed].get(column, "-") for column in columns]
        lines.append(f"| {place.replace('{seed}', str(seed))} | " + " | ".join(cells) + " |")
    return lines, verdicts


def figure(sets: list[tuple[str, Pairs]], rules: dict[str, Any], path: Path) -> bool:
    """Per set, each map's collisions per training episode, claim against reference (one point per map, the diagonal
    for equal): ``path``, if matplotlib (extra ``plots``) is there."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    key, claim, reference = rules["collisions"], rules["claim"], rules["reference"]
    fig, axes = plt.subplots(1, len(sets), figsize=(4.2 * len(sets), 4.2), squeeze=False)
    for ax, (label, found) in zip(axes[0], sets, strict=True):
        x = [float(p[1][key]) for p in found.values()]
        y = [float(p[0][key]) for p in found.values()]
        top = max([*x, *y, 0.05]) * 1.05
        ax.plot([0, top], [0, top], color="grey", linewidth=0.8)
        ax.scatter(x, y, s=14, color="tab:red")
        ax.set(xlim=(0, top), ylim=(0, top), title=label)
        ax.set(
            xlabel=f"{reference}: collisions per training episode", ylabel=f"{claim}: collisions per training episode"
        )
    fig.tight_layout()
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)
    return True


def report(parts: list[Part], out: Path) -> str:
    """Write ``table.md`` under ``out``: the verdicts; per set of comparison parts (a spec's ``rules.parts``: the
    registered set, the replication set) R1-R4 over its pairs, by part, every map; the transfer. Parts without rows
    yet are left out."""
    by_name = {p.part: p for p in parts if not p.rows.empty}
    sets: dict[tuple[str, ...], list[Part]] = {}
    for part in by_name.values():
        if "learned_at" in part.spec["rules"]:
            sets.setdefault(tuple(part.spec["rules"]["parts"]), []).append(part)
    for names, members in sets.items():
        members.sort(key=lambda p: names.index(p.part))
    links = ", ".join(f"[{p.part}/rows.csv]({p.part}/rows.csv)" for p in by_name.values())
    head = ["# 2D-RL across offices", "", f"Rules: [preregistration.md](preregistration.md). Rows: {links}.", ""]
    summary, body, drawn = ["## Verdicts", ""], [], []
    for members in sets.values():
        rules = members[0].spec["rules"]
        claim, reference = rules["claim"], rules["reference"]
        found = pairs(members, claim, reference)
        lines, verdicts = comparison(found, rules)
        label = f"{len(found)} offices ({', '.join(p.part for p in members)})"
        drawn.append((label, found))
        summary += [f"- {label}: " + "; ".join(f"{rule} {text}" for rule, text in verdicts.items()) + "."]
        body += ["", f"## {claim} against {reference}: {label}", "", *lines]
        for part in members:
            body += [
                "",
                f"### {part.part} only (descriptive)",
                "",
                *comparison(pairs([part], claim, reference), rules)[0],
            ]
        body += [
            "",
            "### Every map",
            "",
            *every_map(members, claim, reference, rules["learned_at"], rules["collisions"]),
        ]
    out.mkdir(parents=True, exist_ok=True)
    if drawn and figure(drawn, rules, out / "fig_collisions.png"):
        head += ["![collisions per training episode](fig_collisions.png)", ""]
    transfers = [p for p in by_name.values() if "database" in p.spec["rules"]]
    if transfers:
        lines, verdicts = transfer(by_name, transfers[0].spec["rules"])
        summary += verdicts
        body += ["", "## Transfer to the stand-in robot (NomadOfficeReal-v0)", "", *lines]
    text = "\n".join([*head, *summary, *body]) + "\n"
    (out / "table.md").write_text(text)
    return text
