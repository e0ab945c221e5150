"""What each part of 2D-RL contributes, at the paper's protocol: ``sb3-twodrl-ablation``.

Every arm is a grid of (arm, seed) runs of :func:`~twodrl_bench.runner.run_pair`
(epochs of K learning trials and M test trials, batched envs, resume), in ``<out>/<arm>/``. All arms
share the protocol's settings (the packaged ``a2c.yml`` and ``twoda2c.yml``, whose Nomad entries
differ only in the 2D-RL arguments; PPO's arms ``ppo.yml`` and ``twodppo.yml``); an arm changes only
these (every 2D arm but ``twoda2c`` and ``twodppo`` runs
:class:`~twodrl_bench.variants.VariantTwoDimA2C`, where its modes live):

1. ``a2c``: SB3's A2C.
2. ``a2c_fixed``: A2C at a fixed temperature: TwoDimA2C with ``reward_split="none"`` (the whole
   reward in the reward stream), ``punishment_weight=0`` and no punishment critic loss, which is A2C
   (``tests/test_equivalence.py``), with ``temperature`` set to the ``paper`` arm's mean temperature.
3. ``twod_fixed``: TwoDimA2C (two critics, the utility) at that fixed temperature: no interest.
4. ``paper``: TwoDimA2C, eq. 9 as the paper writes it (``interest="paper", preferences="raw"``),
   with the actor update ``"log_prob"`` (the default before the compensated score), pinned (arms
   2-5 and the relative ones too).
5. ``relative_bounded``, ``relative_raw``, ``learned_bounded``: the options of
   :mod:`twodrl_bench.variants`; ``relative_bound25``: the relative interest on preferences
   bounded to an sd of 2.5 with the floor at 1 (exploratory, derived in ``docs/ablation.md``);
   ``paper_eq10`` and ``bound25_eq10``: ``paper`` and ``relative_bound25`` with eq. 10 taken
   literally (``actor_update="preference"``; exploratory); ``paper_tempered``: ``paper`` with the
   policy gradient of the tempered policy that acted (``actor_update="tempered"``);
   ``paper_compensated``: the same times each action's ``T`` (``actor_update="compensated"``);
   ``paper_skip_uniform``: that without the update of an episode's uniform first move;
   ``relative_skip_uniform``: the relative interest on raw preferences with that update;
   ``learned_skip_uniform``: the learned per-state interest on raw preferences with that update;
   ``twod_fixed_compensated``: ``twod_fixed`` with that update (at a fixed ``T`` no move is uniform).
6. ``twoda2c``: the shipped ``TwoDimA2C`` itself (``V_P`` starts at 0, where the variants keep its
   orthogonal initialisation); ``twoda2c_fixed``: it at a fixed temperature.
7. ``ppo`` and ``twodppo``: SB3's PPO and the shipped ``TwoDimPPO``, on ``ppo.yml`` and
   ``twodppo.yml`` (whose Nomad entries also differ only in the 2D-RL arguments).

The fixed arms run after the ``paper`` arm, whose mean temperature over all its learning steps
(``mean_temperature`` of the rows, weighted by steps) they take unless ``--fixed-temperature`` is
given; it is stored in ``<out>/fixed_temperature.json``.

Per run (:func:`summarize_run`): final test goal rate (last epoch), learned (final goal rate >= 0.8),
the first epoch with a goal rate >= 0.5, shortcut share and reward per step of the last epoch,
collapse (after a goal rate >= 0.8, 3 or more consecutive epochs below 0.5), and, over all learning
steps, the share on which the interest, not a clamp, set the temperature. Per arm (:func:`table`):
means over seeds with 95% intervals (t over seeds; Wilson for the share of seeds that learned).
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from sb3_twodrl.hyperparams import hyperparams_path
from twodrl_bench.grid import check_config, collect_results, pending, run_grid
from twodrl_bench.intervals import mean_ci, wilson
from twodrl_bench.protocol import PRESETS, RunSpec, load_hyperparams, parse_env_kwargs

_LOG_PROB_SCORE = {"actor_update": "log_prob"}
"""The actor update every arm but ``paper_tempered``, ``paper_compensated`` and the eq. 10 arms ran with
(the default then): pinned, so that the arms keep their rows whatever the default becomes."""
_VARIANT = "twoda2c_variant"
"""Every 2D arm runs :class:`~twodrl_bench.variants.VariantTwoDimA2C` (hyperparameters of
``twoda2c.yml``): the arms' interest modes, preferences and actor updates are variants, and they ran
with ``V_P``'s orthogonal initialisation, which the variants keep."""
_BASE_ALGO = {_VARIANT: "twoda2c"}
"""Whose hyperparameter file an arm's algorithm takes."""

ARMS: dict[str, tuple[str, dict[str, Any]]] = {
    "a2c": ("a2c", {}),
    "twoda2c": ("twoda2c", {}),
    "ppo": ("ppo", {}),
    "twodppo": ("twodppo", {}),
    "twoda2c_fixed": ("twoda2c", {}),
    "a2c_fixed": (
        _VARIANT,
        {"reward_split": "none", "punishment_weight": 0.0, "punishment_vf_coef": 0.0, **_LOG_PROB_SCORE},
    ),
    "twod_fixed": (_VARIANT, {**_LOG_PROB_SCORE}),
    "twod_fixed_compensated": (_VARIANT, {"actor_update": "compensated_skip_uniform"}),
    "paper": (_VARIANT, {"interest": "paper", "preferences": "raw", **_LOG_PROB_SCORE}),
    "relative_bounded": (_VARIANT, {"interest": "relative", "preferences": "bounded", **_LOG_PROB_SCORE}),
    "relative_raw": (_VARIANT, {"interest": "relative", "preferences": "raw", **_LOG_PROB_SCORE}),
    "learned_bounded": (_VARIANT, {"interest": "learned", "preferences": "bounded", **_LOG_PROB_SCORE}),
    "relative_bound25": (
        _VARIANT,
        {
            "interest": "relative",
            "preferences": "bounded",
            "preference_bound": 2.5,
            "min_temperature": 1.0,
            **_LOG_PROB_SCORE,
        },
    ),
    "paper_eq10": (_VARIANT, {"interest": "paper", "preferences": "raw", "actor_update": "preference"}),
    "paper_tempered": (_VARIANT, {"interest": "paper", "preferences": "raw", "actor_update": "tempered"}),
    "paper_compensated": (_VARIANT, {"interest": "paper", "preferences": "raw", "actor_update": "compensated"}),
    "paper_skip_uniform": (
        _VARIANT,
        {"interest": "paper", "preferences": "raw", "actor_update": "compensated_skip_uniform"},
    ),
    "relative_skip_uniform": (
        _VARIANT,
        {"interest": "relative", "preferences": "raw", "actor_update": "compensated_skip_uniform"},
    ),
    "learned_skip_uniform": (
        _VARIANT,
        {"interest": "learned", "preferences": "raw", "actor_update": "compensated_skip_uniform"},
    ),
    "bound25_eq10": (
        _VARIANT,
        {
            "interest": "relative",
            "preferences": "bounded",
            "preference_bound": 2.5,
            "min_temperature": 1.0,
            "actor_update": "preference",
        },
    ),
}
FIXED = ("a2c_fixed", "twod_fixed", "twod_fixed_compensated", "twoda2c_fixed")
"""Arms acting at a fixed temperature (that of the ``paper`` arm), raw preferences."""
DEFAULT_ARMS = ("a2c", "a2c_fixed", "twod_fixed", "paper", "learned_skip_uniform")
"""The ablation's five arms: A2C, A2C and TwoDimA2C at the paper arm's mean temperature, eq. 9 as the paper
writes it, and TwoDimA2C's default of its time (``interest="learned"``, pinned so that the arm keeps its rows)."""
METRICS = (
    "learned",
    "final_goal_rate",
    "epochs_to_half",
    "shortcut_share",
    "reward_per_step",
    "interest_share",
)


def file_algo(arm: str) -> str:
    """The algorithm whose hyperparameter file ``arm`` takes."""
    algo = ARMS[arm][0]
    return _BASE_ALGO.get(algo, algo)


def arm_hyperparams(arm: str, base: dict[str, dict[str, Any]], temperature: float | None) -> tuple[str, dict]:
    """The algorithm name and hyperparameters of ``arm``: ``base[algo]`` with the arm's 2D settings."""
    if arm not in ARMS:
        raise ValueError(f"arm must be one of {sorted(ARMS)}, got {arm!r}")
    algo, overrides = ARMS[arm]
    hp = {**base[file_algo(arm)], **overrides}
    if arm in FIXED:
        if temperature is None or not temperature > 0:
            raise ValueError(f"arm {arm!r} needs a positive fixed temperature, got {temperature!r}")
        hp["temperature"] = float(temperature)
        if algo == _VARIANT:
            hp["preferences"] = "raw"
    return algo, hp


def mean_temperature(rows: Any) -> float:
    """Mean temperature over all learning steps of ``rows`` (a results DataFrame), weighted by steps."""
    steps = rows.groupby("seed")["env_steps"].diff().fillna(rows["env_steps"])
    keep = rows["mean_temperature"].notna()
    if not keep.any():
        raise ValueError("rows have no mean_temperature: the paper arm has not run")
    return float(np.average(rows.loc[keep, "mean_temperature"], weights=steps[keep]))


def summarize_run(rows: Any) -> dict[str, float]:
    """The per-run metrics of one (arm, seed)'s rows, in epoch order."""
    rates = rows["goal_rate"].to_numpy(dtype=float)
    steps = np.diff(rows["env_steps"].to_numpy(dtype=float), prepend=0.0)
    share = rows["interest_share"].to_numpy(dtype=float)
    known = ~np.isnan(share)
    half = np.flatnonzero(rates >= 0.5)
    peak = np.flatnonzero(rates >= 0.8)
    longest = run = 0
    for below in rates[peak[0] :] < 0.5 if peak.size else []:
        run = run + 1 if below else 0
        longest = max(longest, run)
    last = rows.iloc[-1]
    return {
        "learned": float(rates[-1] >= 0.8),
        "final_goal_rate": float(rates[-1]),
        "epochs_to_half": float(half[0] + 1) if half.size else math.nan,
        "shortcut_share": float(last["shortcut_share"]),
        "reward_per_step": float(last["reward_per_step"]),
        "interest_share": float(np.average(share[known], weights=steps[known])) if known.any() else math.nan,
        "collapsed": float(longest >= 3),
    }


def interval(values: list[float], count: bool = False) -> tuple[float, float, float, int]:
    """Mean and 95% interval over seeds (Wilson for a share of seeds, t otherwise), NaNs left out."""
    mean, half, n = mean_ci(values)
    if count and n:
        return (mean, *wilson(round(mean * n), n), n)
    return mean, mean - half, mean + half, n


def summaries(frames: dict[str, Any]) -> dict[str, list[dict[str, float]]]:
    """Per arm, the :func:`summarize_run` of each finished seed of its results DataFrame."""
    return {
        arm: [{"seed": seed, **summarize_run(rows)} for seed, rows in df.groupby("seed")] for arm, df in frames.items()
    }


def table(runs: dict[str, list[dict[str, float]]]) -> str:
    """Markdown: one row per arm, each metric's mean [95% interval] (n seeds), collapses counted."""
    lines = ["| arm | seeds | " + " | ".join(METRICS) + " | collapsed |", "|---" * (len(METRICS) + 3) + "|"]
    for arm, mine in runs.items():
        if not mine:
            continue
        cells = []
        for key in METRICS:
            mean, low, high, n = interval([r[key] for r in mine], count=key == "learned")
            digits = 1 if key == "epochs_to_half" else 3 if key == "reward_per_step" else 2
            cells.append("-" if n == 0 else f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}] (n={n})")
        collapsed = int(sum(r["collapsed"] for r in mine))
        lines.append(f"| {arm} | {len(mine)} | " + " | ".join(cells) + f" | {collapsed} |")
    return "\n".join(lines)


def figure(frames: dict[str, Any], runs: dict[str, list[dict[str, float]]], path: Path) -> None:
    """Bars of the per-arm metrics with their intervals, and each arm's mean test goal rate per epoch."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arms = [arm for arm, mine in runs.items() if mine]
    palette = plt.get_cmap("tab10" if len(arms) <= 10 else "tab20")
    fig, axes = plt.subplots(1, len(METRICS) + 1, figsize=(3.6 * (len(METRICS) + 1), 3.6))
    for ax, key in zip(axes, METRICS, strict=False):
        for i, arm in enumerate(arms):
            mean, low, high, n = interval([r[key] for r in runs[arm]], count=key == "learned")
            if n:
                error = None if math.isnan(low) else [[max(mean - low, 0.0)], [max(high - mean, 0.0)]]
                ax.bar(i, mean, yerr=error, capsize=4, color=palette(i))
        ax.set_xticks(range(len(arms)), arms, rotation=40, ha="right")
        ax.set_title(key)
    ax = axes[-1]
    for i, arm in enumerate(arms):
        curve = frames[arm].groupby("epoch")["goal_rate"].mean()
        ax.plot(curve.index, curve.to_numpy(), color=palette(i), label=arm)
    ax.set_xlabel("epoch")
    ax.set_title("test goal rate (mean over seeds)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", default="NomadOffice-v0", help="Gymnasium ID (default: %(default)s)")
    p.add_argument("--arms", nargs="+", choices=sorted(ARMS), default=list(DEFAULT_ARMS))
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    p.add_argument("--epochs", type=int, default=50)
    p.add_argument("--learn-episodes", "-K", type=int, default=PRESETS["paper"]["learn_episodes"])
    p.add_argument("--test-episodes", "-M", type=int, default=PRESETS["paper"]["test_episodes"])
    p.add_argument("--fixed-temperature", type=float, help="default: the paper arm's measured mean temperature")
    p.add_argument("--hyperparams-dir", help="folder of the arms' <algo>.yml (default: the packaged files)")
    p.add_argument("--checkpoint-every", type=int, default=10, help="epochs between checkpoints (0: none)")
    p.add_argument("--out", type=Path, default=Path("runs") / "ablation")
    p.add_argument("--backend", choices=("process", "ray", "serial"), default="process")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    p.add_argument("--gym-packages", nargs="*", default=["envs"], help="modules that register the env")
    p.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY:VALUE",
        help="shared settings changed for every arm (a factor of a factorial), e.g. ent_coef:0.01 n_envs:1",
    )
    p.add_argument("--env-kwargs", nargs="*", metavar="KEY:VALUE", help="env arguments, e.g. observation:'cell'")
    p.add_argument(
        "--from-results",
        nargs="+",
        type=Path,
        metavar="CSV",
        help="no runs: the table and figure of these results files (an 'arm' column, one arm in one file only)",
    )
    return p.parse_args(argv)


def _run_arms(args: argparse.Namespace, arms: list[str], base: dict, temperature: float | None) -> None:
    specs = []
    env_kwargs = parse_env_kwargs(args.env_kwargs)
    for arm in arms:
        algo, hp = arm_hyperparams(arm, base, temperature)
        out = args.out / arm
        config = {
            "env_id": args.env,
            "epochs": args.epochs,
            "learn_episodes": args.learn_episodes,
            "test_episodes": args.test_episodes,
            "vec_env": "auto",
            "env_kwargs": env_kwargs,
            "hyperparams": {algo: {k: repr(v) for k, v in hp.items()}},
        }
        check_config(out, config)
        specs += [
            RunSpec(
                env_id=args.env,
                algo=algo,
                seed=seed,
                epochs=args.epochs,
                learn_episodes=args.learn_episodes,
                test_episodes=args.test_episodes,
                hyperparams=hp,
                out_dir=str(out),
                gym_packages=list(args.gym_packages),
                checkpoint_every=args.checkpoint_every,
                tensorboard=False,
                env_kwargs=env_kwargs,
            )
            for seed in args.seeds
        ]
    run_grid(pending(specs), args.backend, args.workers)


def frames_from_results(paths: list[Path]) -> dict[str, Any]:
    """Per arm, its rows from results files with an ``arm`` column (as ``docs/figures/ablation_*_results.csv``).

    :raises ValueError: if an arm's rows are in two files (label them apart first, e.g. by temperature)
    """
    import pandas as pd

    frames: dict[str, Any] = {}
    for path in paths:
        df = pd.read_csv(path)
        if "arm" not in df.columns:
            raise ValueError(f"from_results: {path} has no 'arm' column")
        for arm, rows in df.groupby("arm", sort=False):
            if arm in frames:
                raise ValueError(f"from_results: arm {arm!r} is in more than one file ({path} among them)")
            frames[arm] = rows.sort_values(["seed", "epoch"]).reset_index(drop=True)
    return frames


def report(frames: dict[str, Any], out: Path) -> dict[str, list[dict[str, float]]]:
    """Write ``table.md``, ``runs.json`` and ``ablation.png`` of ``frames`` under ``out``; the per-run summaries."""
    runs = summaries(frames)
    text = table(runs)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text + "\n")
    (out / "runs.json").write_text(json.dumps(runs, indent=1))
    figure(frames, runs, out / "ablation.png")
    print(text)
    return runs


def ablation(argv: list[str] | None = None) -> dict[str, list[dict[str, float]]]:
    """Run (or resume) the arms of ``argv``, or read ``--from-results``; write ``table.md`` and
    ``ablation.png``; the per-run summaries."""
    args = parse_args(argv)
    if args.from_results:
        return report(frames_from_results(args.from_results), args.out)
    for package in args.gym_packages:
        importlib.import_module(package)
    shared = parse_env_kwargs(args.set, "--set")
    files = {algo: hyperparams_path(algo, args.hyperparams_dir) for algo in sorted(set(map(file_algo, args.arms)))}
    base = {algo: {**load_hyperparams(path, args.env), **shared} for algo, path in files.items()}
    free = [arm for arm in args.arms if arm not in FIXED]
    fixed = [arm for arm in args.arms if arm in FIXED]
    _run_arms(args, free, base, None)
    if fixed:
        temperature = args.fixed_temperature
        if temperature is None:
            temperature = mean_temperature(collect_results(args.out / "paper"))
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "fixed_temperature.json").write_text(json.dumps({"temperature": temperature}))
        _run_arms(args, fixed, base, temperature)
    return report({arm: collect_results(args.out / arm) for arm in args.arms}, args.out)


def main(argv: list[str] | None = None) -> None:
    ablation(argv)
