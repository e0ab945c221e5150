"""Figures 3-5 of the 2D-RL paper and its results tables from an epoch study's rows (extra ``plots``).

The reports draw them (``sb3-twodrl-bench report quick_preset`` redraws them from the run folders).
Curves: mean over seeds per epoch, band: 95% confidence interval of that mean (Student t over
seeds; a seed whose share is undefined at an epoch, because none of its test episodes committed
to a route, is left out of that epoch's share).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from twodrl_bench.intervals import mean_ci

STYLE = {  # the paper: proposed method solid, conventional actor-critic dotted
    "twoda2c": {"label": "2D-RL (TwoDimA2C)", "linestyle": "-", "color": "tab:red"},
    "a2c": {"label": "actor-critic (A2C)", "linestyle": ":", "color": "tab:blue"},
    "ppo": {"label": "PPO", "linestyle": "-.", "color": "tab:green"},
}
PAPER_WINDOWS = ((1, 150), (151, 400), (401, 700), (701, 1000))
"""Epoch windows of the paper's statements (section 3.4.2): A2C on the detour after about 150 epochs,
2D-RL's routes 50:50 before 400 and its goal rate 80-90% after 400, A2C's about 90% after 700."""
TABLE_METRICS = (("goal_rate", ".2f"), ("reward_per_step", ".4f"), ("shortcut_share", ".2f"), ("collision_rate", ".2f"))
FIGURES = [
    ("fig3_goal_rate.png", "goal_rate", "goal reaching probability (test)", (0.0, 1.0)),
    ("fig4_reward_per_step.png", "reward_per_step", "reward per step (test)", None),
    ("fig5_route_share.png", "shortcut_share", "shortcut share of routed test episodes", (0.0, 1.0)),
]


def curves(df: pd.DataFrame, metric: str) -> dict[str, pd.DataFrame]:
    out = {}
    for algo, g in df.groupby("algo"):
        rows = []
        for epoch, e in g.groupby("epoch"):
            mean, half, n = mean_ci(e[metric].to_numpy())
            rows.append({"epoch": epoch, "mean": mean, "half": half, "n": n})
        out[str(algo)] = pd.DataFrame(rows).sort_values("epoch")
    return out


def make_figures(df: pd.DataFrame, out_dir: str | Path, title: str = "") -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for filename, metric, ylabel, ylim in FIGURES:
        fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
        for algo, c in sorted(curves(df, metric).items(), key=lambda kv: kv[0] != "twoda2c"):
            style = STYLE.get(algo, {"label": algo, "linestyle": "--", "color": None})
            x, y = c["epoch"].to_numpy(), c["mean"].to_numpy()
            half = np.nan_to_num(c["half"].to_numpy(), nan=0.0)
            ax.plot(x, y, linestyle=style["linestyle"], color=style["color"], label=style["label"], linewidth=1.8)
            ax.fill_between(x, y - half, y + half, color=style["color"], alpha=0.2, linewidth=0)
        if metric == "shortcut_share":
            ax.axhline(0.5, color="grey", linewidth=0.8, linestyle="--")
        if ylim is not None:
            ax.set_ylim(ylim[0] - 0.02, ylim[1] + 0.02)
        ax.set_xlabel("epoch")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
        fig.tight_layout()
        path = out_dir / filename
        fig.savefig(path)
        plt.close(fig)
        paths.append(path)
    return paths


def final_values(df: pd.DataFrame, last_fraction: float = 0.1) -> pd.DataFrame:
    """Per (algo, seed): the mean over the last ``last_fraction`` of the epochs (at least one)."""
    n_last = max(1, round(float(df["epoch"].max()) * last_fraction))
    first = df["epoch"].max() - n_last + 1
    tail = df[df["epoch"] >= first]
    metrics = ["goal_rate", "reward_per_step", "shortcut_share", "collision_rate"]
    return tail.groupby(["algo", "seed"])[metrics].mean().reset_index().assign(first_epoch=first)


def _cell(values: np.ndarray, fmt: str) -> str:
    """Mean ± 95% half-width over the finite values ("n/a" if none, the mean alone if one)."""
    mean, half, n = mean_ci(values)
    return "n/a" if n == 0 else f"{mean:{fmt}} ± {half:{fmt}}" if n > 1 else f"{mean:{fmt}}"


def summary_table(df: pd.DataFrame, env_id: str = "", k: int | None = None, m: int | None = None) -> str:
    """Markdown table: end-of-run values, mean and 95% interval over seeds."""
    if df.empty:
        return "(no results)\n"
    fin = final_values(df)
    first, last = int(fin["first_epoch"].iloc[0]), int(df["epoch"].max())
    lines = [
        f"Env `{env_id}`, {last} epochs"
        + (f" of K={k} learning + M={m} test episodes" if k else "")
        + f"; values averaged over epochs {first}-{last} per seed, then mean ± 95% CI over seeds.",
        "",
        "| algorithm | seeds | goal rate | reward per step | shortcut share | collision rate |",
        "|---|---|---|---|---|---|",
    ]
    for algo in sorted(fin["algo"].unique(), key=lambda a: a != "twoda2c"):
        f = fin[fin["algo"] == algo]
        cells = [_cell(f[metric].to_numpy(), fmt) for metric, fmt in TABLE_METRICS]
        label = STYLE.get(algo, {"label": algo})["label"]
        lines.append(f"| {label} | {f['seed'].nunique()} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def window_table(df: pd.DataFrame, windows: tuple[tuple[int, int], ...] = PAPER_WINDOWS) -> str:
    """Markdown table: per algorithm and epoch window (cut to the epochs run), each seed's mean over
    the window, then mean ± 95% CI over seeds (a share undefined in a whole window leaves the seed out)."""
    last = int(df["epoch"].max()) if len(df) else 0
    spans = [(lo, min(hi, last)) for lo, hi in windows if lo <= last]
    if not spans:
        return "(no results)\n"
    lines = [
        "| algorithm | epochs | seeds | goal rate | reward per step | shortcut share | collision rate |",
        "|---|---|---|---|---|---|---|",
    ]
    for algo in sorted(df["algo"].unique(), key=lambda a: a != "twoda2c"):
        label = STYLE.get(algo, {"label": algo})["label"]
        for lo, hi in spans:
            window = df[(df["algo"] == algo) & df["epoch"].between(lo, hi)]
            per_seed = window.groupby("seed")[[m for m, _ in TABLE_METRICS]].mean()
            cells = [_cell(per_seed[metric].to_numpy(), fmt) for metric, fmt in TABLE_METRICS]
            lines.append(f"| {label} | {lo}-{hi} | {len(per_seed)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
