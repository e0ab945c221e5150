"""Paper section 3.5: does database training transfer to the "real" robot? The transfer's report.

A transfer spec is an epoch protocol with ``transfer: {env, trials, seed}``: each (arm, seed) trains on the
spec's env, then its final deterministic policy runs ``trials`` trials on ``env`` (default
``NomadOfficeReal-v0``, the stand-in robot) with the held-out seed, and 10 in its own training env
(:func:`twodrl_bench.trials.transfer_columns`; the counts are in the last epoch's row). The spec's
``env_kwargs`` go to both envs (``observe_odometry: false``: sensors only). One table row per (arm, part):
the paper's 10 trials per seed, success, shortcut and collision rates over all trials as means over
seeds with 95% t-intervals, the pooled successes with a Wilson interval, and the success rate of the
same policies in their own training env (did they learn at all?).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from twodrl_bench.intervals import mean_ci, wilson
from twodrl_bench.protocol import PAPER_TRIALS
from twodrl_bench.reports import Part


@dataclass
class TransferRow:
    algo: str
    trained_on: str
    seeds: list[int]
    trials_per_seed: int
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    paper_successes: list[int] = field(default_factory=list)
    successes: list[int] = field(default_factory=list)
    shortcut: list[int] = field(default_factory=list)
    collisions: list[int] = field(default_factory=list)
    timeouts: list[int] = field(default_factory=list)
    train_env_success: list[float] = field(default_factory=list)


def over_seeds(values: list[float]) -> str:
    """``mean [low, high]``: the mean over seeds with its 95% t-interval."""
    mean, half, n = mean_ci(values)
    return "-" if n == 0 else f"{mean:.2f}" if n == 1 else f"{mean:.2f} [{mean - half:.2f}, {mean + half:.2f}]"


def table(rows: list[TransferRow]) -> str:
    """Markdown: rates are means over seeds with 95% t-intervals; successes / N pooled with a Wilson interval."""
    lines = [
        f"| algorithm | trained on | paper's {PAPER_TRIALS} trials, successes per seed | success rate | successes / N "
        "(Wilson) | shortcut share of successes | collision rate | time-out rate | success in training env |",
        "|" + " --- |" * 9,
    ]
    for row in rows:
        n = row.trials_per_seed
        k, total = sum(row.successes), n * len(row.seeds)
        lo, hi = wilson(k, total)
        share = f"{sum(row.shortcut) / k:.2f}" if k else "-"
        lines.append(
            f"| {row.algo} | {row.trained_on} | {', '.join(map(str, row.paper_successes))} | "
            f"{over_seeds([x / n for x in row.successes])} | {k} / {total} ({lo:.0%}-{hi:.0%}) | {share} | "
            f"{over_seeds([x / n for x in row.collisions])} | {over_seeds([x / n for x in row.timeouts])} | "
            f"{over_seeds(row.train_env_success)} |"
        )
    return "\n".join(lines)


def transfer_rows(part: Part) -> list[TransferRow]:
    """Per arm of ``part``, its seeds' transfer counts (the last epoch's row of each finished job)."""
    if "transfer" not in part.spec["protocol"]:
        raise ValueError(f"{part.name}: the transfer report needs a protocol with a transfer key")
    trials = part.spec["protocol"]["transfer"]["trials"]
    rows = []
    for arm in part.spec["arms"]:
        mine = part.rows[part.rows["arm"] == arm] if not part.rows.empty else part.rows
        if mine.empty:
            continue
        last = mine.sort_values(["seed", "epoch"]).groupby("seed").tail(1)
        row = TransferRow(arm, part.spec["env"], [int(s) for s in last["seed"]], trials, part.spec["env_kwargs"])
        row.paper_successes = [int(v) for v in last["transfer_paper_successes"]]
        row.successes = [int(v) for v in last["transfer_success"]]
        row.shortcut = [int(v) for v in last["transfer_shortcut"]]
        row.collisions = [int(v) for v in last["transfer_collision"]]
        row.timeouts = [int(v) for v in last["transfer_timeout"]]
        row.train_env_success = [float(v) for v in last["own_env_success"]]
        rows.append(row)
    return rows


def report(parts: list[Part], out: Path) -> str:
    """Write ``table.md`` and ``transfer.json`` under ``out``: one table per observation setting (env_kwargs)."""
    import json

    by_setting: dict[str, list[TransferRow]] = {}
    heads: dict[str, str] = {}
    for part in parts:
        kwargs = part.spec["env_kwargs"]
        key = json.dumps(kwargs, sort_keys=True)
        transfer = part.spec["protocol"]["transfer"]
        heads[key] = (
            f"Transfer to {transfer['env']} {kwargs or ''}: {part.spec['protocol']['epochs']} epochs of training, "
            f"seeds {part.spec['seeds']}, {transfer['trials']} deterministic trials (held-out seed {transfer['seed']})"
        )
        by_setting.setdefault(key, []).extend(transfer_rows(part))
    text = "\n\n".join(f"{heads[key]}\n\n{table(rows)}" for key, rows in by_setting.items())
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    every = [asdict(r) for rows in by_setting.values() for r in rows]
    (out / "transfer.json").write_text(json.dumps(every, indent=1))
    return text
