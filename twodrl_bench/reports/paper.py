"""The paper's experiment (section 3.4): figures 3-5, the summary, and the end-of-run comparison.

Per part (env): ``fig3_goal_rate.png``, ``fig4_reward_per_step.png``, ``fig5_route_share.png`` (mean over
seeds per epoch with a 95% band, :func:`twodrl_bench.plots.make_figures`) and ``summary.md`` (end-of-run
values and the paper's epoch windows). ``table.md`` holds every part's summary. The printed text gives,
per part, the reward per step over the last 10% of the epochs (28-30 of 30) per arm as the mean and 95%
t-interval over seeds, the difference of the two compared arms (``rules.compare``, default the first two
arms) with a 95% Welch interval, and the paths of the summary and figures.
"""

from __future__ import annotations

from pathlib import Path

from twodrl_bench.intervals import mean_ci, welch_ci
from twodrl_bench.plots import final_values, make_figures, summary_table, window_table
from twodrl_bench.reports import Part


def compared(part: Part) -> list[str]:
    """The two arms whose difference is reported: ``rules.compare`` or the spec's first two arms."""
    arms = part.spec["rules"].get("compare", list(part.spec["arms"])[:2])
    if len(arms) != 2 or not set(arms) <= set(part.spec["arms"]):
        raise ValueError(f"{part.name}: rules.compare must name two of the arms {list(part.spec['arms'])}, got {arms}")
    return arms


def end_of_run(part: Part) -> str:
    """Reward per step over the last 10% of the epochs: per arm mean ± 95% interval, and the difference (Welch)."""
    df = part.rows.assign(algo=part.rows["arm"])
    fin = final_values(df)
    first, last = int(fin["first_epoch"].iloc[0]), int(df["epoch"].max())
    per_arm = {arm: g["reward_per_step"].to_numpy() for arm, g in fin.groupby("algo")}
    lines = [f"{part.spec['env']}: reward per step over epochs {first}-{last}, mean ± 95% interval over seeds"]
    for arm in part.spec["arms"]:
        if arm in per_arm:
            mean, half, n = mean_ci(per_arm[arm])
            interval = f" ± {half:.4f}" if n >= 2 else ""  # one seed: no interval
            lines.append(f"  {arm}: {mean:.4f}{interval} (n={n})")
    a, b = compared(part)
    if len(per_arm.get(a, [])) >= 2 and len(per_arm.get(b, [])) >= 2:
        diff, half = welch_ci(per_arm[a], per_arm[b])
        lines.append(f"  {a} - {b}: {diff:+.4f} [{diff - half:+.4f}, {diff + half:+.4f}] (95% Welch)")
    return "\n".join(lines)


def report(parts: list[Part], out: Path) -> str:
    """Write the figures and ``summary.md`` per part and ``table.md``; the end-of-run comparison and the paths."""
    texts, tables = [], []
    for part in parts:
        if part.rows.empty:
            texts.append(f"{part.name}: no rows yet")
            continue
        target = out / part.part if part.part else out
        df = part.rows.assign(algo=part.rows["arm"])
        protocol = part.spec["protocol"]
        k, m = protocol["learn_episodes"], protocol["test_episodes"]
        figures = make_figures(df, target, title=f"{part.spec['env']}: K={k}, M={m}, {df['seed'].nunique()} seeds")
        summary = summary_table(df, env_id=part.spec["env"], k=k, m=m) + "\nBy the paper's epoch windows:\n\n"
        summary += window_table(df)
        (target / "summary.md").write_text(summary)
        tables.append(f"## {part.name}\n\n{summary}")
        paths = "\n".join(f"  {p}" for p in [target / "summary.md", *figures])
        texts.append(f"{end_of_run(part)}\n{paths}")
    (out / "table.md").write_text("\n".join(tables))
    return "\n\n".join(texts)
