"""A baseline's settings search at the paper's protocol: its report.

A search is a spec with a ``grid`` (``{algo, points: {key: [values]}, override}``): each point of the
product is an arm (:func:`twodrl_bench.spec.point_name`), run for the protocol's epochs per seed. Each
point is scored two ways: the mean test goal rate over all its epochs (the area under figure 3's
curve) and the mean test reward per step over the epochs ``rules.score_epochs`` (default: the last
half); ``rules.rank_by`` (default ``reward_per_step``) names the score that picks the point, the
other breaks ties. A point's rows come from its own settings only: the runner refuses a folder
whose stored spec gives an arm other settings. (Optuna searches stay rl-zoo3's ``-optimize``.)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_bench.reports import Part

SCORES = ("goal_rate", "reward_per_step")


def score(rows: Any, first: int, last: int) -> dict[str, Any]:
    """One point's rows (every seed): both scores, per seed and averaged, and each seed's first epoch at a
    test goal rate >= 0.5 (``None``: never)."""
    per_seed = {}
    for seed, g in rows.groupby("seed"):
        window = g.loc[g["epoch"].between(first, last), "reward_per_step"].to_numpy(dtype=float)
        half = g.loc[g["goal_rate"] >= 0.5, "epoch"]
        per_seed[int(seed)] = {
            "goal_rate": float(g["goal_rate"].mean()),
            "reward_per_step": float(window.mean()) if window.size else math.nan,
            "first_half": int(half.min()) if len(half) else None,
        }
    means = {key: float(np.mean([s[key] for s in per_seed.values()])) for key in SCORES}
    return {**means, "per_seed": per_seed}


def _ranking(rank_by: str) -> tuple[str, ...]:
    """The scores in the order they rank points: ``rank_by``, then the other (ties)."""
    return (rank_by, *(k for k in SCORES if k != rank_by))


def score_window(part: Part) -> tuple[int, int]:
    """``rules.score_epochs`` (default: the last half of the epochs).

    :raises ValueError: if it is not 1 <= FIRST <= LAST <= epochs
    """
    epochs = part.spec["protocol"]["epochs"]
    first, last = part.spec["rules"].get("score_epochs", (epochs // 2 + 1, epochs))
    if not 1 <= first <= last <= epochs:
        raise ValueError(f"{part.name}: rules.score_epochs must be 1 <= FIRST <= LAST <= {epochs}, got {first} {last}")
    return first, last


def rank(part: Part) -> list[dict[str, Any]]:
    """Every point with rows, with its scores, best first."""
    rank_by = part.spec["rules"].get("rank_by", "reward_per_step")
    if rank_by not in SCORES:
        raise ValueError(f"{part.name}: rules.rank_by must be one of {SCORES}, got {rank_by!r}")
    first, last = score_window(part)
    keys = list(part.spec["grid"]["points"])
    results = []
    for arm, rows in part.rows.groupby("arm", sort=False):
        point = {key: part.spec["arms"][arm]["override"][key] for key in keys}
        results.append({**point, **score(rows, first, last)})
    order = _ranking(rank_by)
    results.sort(key=lambda r: tuple(-r[k] if math.isfinite(r[k]) else math.inf for k in order))
    return results


def table(part: Part, results: list[dict[str, Any]]) -> str:
    """Markdown: one row per point, best first, with both scores per seed."""
    protocol, keys = part.spec["protocol"], list(part.spec["grid"]["points"])
    first, last = score_window(part)
    head = (
        f"{part.spec['grid']['algo']} on {part.spec['env']}, {protocol['epochs']} epochs of "
        f"K={protocol['learn_episodes']}, M={protocol['test_episodes']}, seeds {part.spec['seeds']}, "
        f"ranked by {part.spec['rules'].get('rank_by', 'reward_per_step')}\n\n"
    )
    cols = [*keys, "mean test goal rate", f"reward per step, epochs {first}-{last}", "per seed", "first epoch >= 0.5"]
    lines = ["| " + " | ".join(cols) + " |", "|---" * len(cols) + "|"]
    for r in results:
        seeds = r["per_seed"].values()
        cells = [f"{r[k]:g}" if isinstance(r[k], float) else str(r[k]) for k in keys]
        cells += [f"{r['goal_rate']:.2f}", f"{r['reward_per_step']:.4f}"]
        cells.append(", ".join(f"{s['reward_per_step']:.4f}" for s in seeds))
        cells.append(", ".join("-" if s["first_half"] is None else str(s["first_half"]) for s in seeds))
        lines.append("| " + " | ".join(cells) + " |")
    return head + "\n".join(lines)


def report(parts: list[Part], out: Path) -> str:
    """Write ``table.md`` (each part's points, best first) under ``out``; the tables."""
    texts = []
    for part in parts:
        if "grid" not in part.spec:
            raise ValueError(f"{part.name}: the search report needs a spec with a grid")
        texts.append(table(part, rank(part)))
    text = "\n\n".join(texts)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    return text
