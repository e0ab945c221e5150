"""Do the two stand-in robots agree? The report of the ``stand_ins`` study (results/stand_ins/preregistration.md).

Each part trains on one env (exact readings or a recorded database; generated offices or the paper's), keeps the
policy of its best goal check, and runs 100 deterministic trials from the map's start on the physics robot and on
the artifact model (the rows' ``mujoco_*`` and ``real_*`` counts). Per training env (simulator, database: the
generated offices' part and the office's together) and arm: rule S1, the paired difference of success shares
MuJoCo minus Real with its 95% t interval and the verdict by ``rules.agree_within``; the offices where both robots
put the policy on the same side of 0.8; the success shares on each robot. Then every policy's row.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from sb3_twodrl.callbacks import SUCCESS_THRESHOLD
from twodrl_bench.intervals import mean_ci
from twodrl_bench.reports import Part


def verdict(low: float, high: float, within: float) -> str:
    """S1: ``agree`` if [low, high] lies within [-within, +within], ``disagree`` if it excludes 0 and reaches
    beyond, else ``undecided`` (also where the interval is not defined)."""
    if not (math.isfinite(low) and math.isfinite(high)):
        return "undecided"
    if -within <= low and high <= within:
        return "agree"
    return "disagree" if low > 0 or high < 0 else "undecided"


def _shares(rows: pd.DataFrame) -> pd.DataFrame:
    trials = rows[["mujoco_success", "mujoco_collision", "mujoco_timeout"]].astype(float).sum(axis=1)
    return rows.assign(
        trials=trials,
        mujoco=rows["mujoco_success"].astype(float) / trials,
        real=rows["real_success"].astype(float) / trials,
    )


def _interval(values: list[float]) -> tuple[float, float, float]:
    mean, half, _ = mean_ci(values)
    return mean, mean - half, mean + half


def report(parts: list[Part], out: Path) -> str:
    """Write ``table.md`` under ``out`` (module docstring); the text."""
    within = float(parts[0].spec["rules"]["agree_within"])
    frames = []
    for part in parts:
        if part.rows is None or len(part.rows) == 0:
            continue
        trained = "database" if part.spec["env"].startswith("NomadOfficeMemorable") else "simulator"
        office = part.spec.get("env_kwargs", {}).get("map", "office")
        maps = [office.replace("{seed}", str(s)) for s in part.rows["seed"]]
        frames.append(_shares(part.rows).assign(trained_on=trained, map=maps))
    if not frames:
        return "stand_ins: no rows yet"
    rows = pd.concat(frames, ignore_index=True)
    lines = [
        f"Rule S1: success share on the physics robot (MuJoCo) minus on the artifact model (Real), paired by office, "
        f"mean [95% t interval]; agree: the interval within +-{within}; disagree: it excludes 0 and reaches beyond.",
        "",
        "| trained on | arm | offices | MuJoCo, mean | Real, mean | MuJoCo minus Real | S1 | "
        f"same side of {SUCCESS_THRESHOLD} |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for trained in ("simulator", "database"):
        for arm in ("twoda2c", "a2c"):
            group = rows[(rows["trained_on"] == trained) & (rows["arm"] == arm)]
            if group.empty:
                continue
            difference = (group["mujoco"] - group["real"]).tolist()
            mean, low, high = _interval(difference)
            same = int(np.sum((group["mujoco"] >= SUCCESS_THRESHOLD) == (group["real"] >= SUCCESS_THRESHOLD)))
            lines.append(
                f"| {trained} | {arm} | {len(group)} | {group['mujoco'].mean():.3f} | {group['real'].mean():.3f} | "
                f"{mean:+.3f} [{low:+.3f}, {high:+.3f}] | {verdict(low, high, within)} | {same}/{len(group)} |"
            )
    lines += [
        "",
        "Every policy: successes, collisions and time-outs of its trials on each robot; its own env's final goal rate "
        "(20 episodes from the start); the check it was kept at.",
        "",
        "| trained on | map | arm | MuJoCo success / collision / time-out | Real success / collision / time-out | "
        "own env | kept at |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for _, r in rows.sort_values(["trained_on", "map", "arm"], ascending=[False, True, False]).iterrows():
        lines.append(
            f"| {r['trained_on']} | {r['map']} | {r['arm']} | {int(r['mujoco_success'])} / "
            f"{int(r['mujoco_collision'])} / {int(r['mujoco_timeout'])} | {int(r['real_success'])} / "
            f"{int(r['real_collision'])} / {int(r['real_timeout'])} | {float(r['final_success_share']):.2f} | "
            f"{r['kept_at']} |"
        )
    text = "\n".join(lines) + "\n"
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text)
    return text
