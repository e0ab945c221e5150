"""Benchmark on public tasks: ``sb3-twodrl-benchmark --env TASK --algos ARM ...``.

Each (arm, seed) trains with rl-zoo3 itself (``rl_zoo3.train``) at the task's rl-zoo3 entry, the
same for a stock arm (``a2c``, ``ppo``) and its 2D-RL arm (``twoda2c``, ``twodppo``), which adds
the task's pre-registered 2D-RL arguments (docs/benchmark.md); an arm ``<2d algo>-<variant>`` uses
one of the task's other pre-registered splits. The training envs' ``Monitor`` records every
training episode's return and punishment events (the task's ``info`` key), from which come the
learning curve and the training event rates; the final model then runs ``--episodes``
deterministic episodes on a fresh env seeded apart from training (with the run's ``VecNormalize``
statistics, frozen, where the entry normalises).

Resume: a finished (arm, seed) row is kept in ``<out>/<task>/rows.json`` (with the settings it was
made with in ``settings.json``, as :mod:`.non_regression` does) and never recomputed; an
interrupted one starts again from scratch (its partial logs removed), which gives the row an
uninterrupted run gives (training is seeded and single-threaded), ``wall_s`` aside.
Requires the ``zoo`` and ``bench`` extras; the table's intervals and the figure the ``plots`` extra.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import json
import math
import multiprocessing as mp
import shutil
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_bench.checkpoint import atomic_write_bytes
from twodrl_bench.intervals import mean_ci, welch_ci, wilson
from twodrl_bench.non_regression import EVAL_SEED, open_record

Row = dict[str, Any]
STOCK = {"twoda2c": "a2c", "twodppo": "ppo"}
"""The stock algorithm each 2D-RL algorithm is compared with."""
CURVE_BINS = 20
"""Learning-curve points: training episodes binned by the timestep at which they ended."""


@dataclass(frozen=True)
class Task:
    """A benchmark task: the env both arms train on, whose rl-zoo3 entries, and the pre-registered 2D-RL choices."""

    env_id: str
    zoo_id: str
    """The rl-zoo3 entry whose settings (hyperparams/<algo>.yml) both arms use."""
    algos: tuple[str, ...]
    """The stock algorithms the task is run with."""
    two_dim: dict[str, Any]
    """The 2D-RL arguments of arm ``twoda2c`` / ``twodppo``."""
    variants: dict[str, dict[str, Any]] = field(default_factory=dict)
    """Other pre-registered 2D-RL arguments, arm ``twoda2c-<name>`` / ``twodppo-<name>``."""
    events: str | None = None
    """The ``info`` key holding the episode's punishment events so far (recorded by the Monitor)."""
    overrides: dict[str, Any] = field(default_factory=dict)
    """Settings over the rl-zoo3 entry, for both arms (documented deviations)."""
    paths: tuple[int, ...] = ()
    """Lengths of the event-free deterministic paths whose share of seeds the table counts (CliffWalking's rows)."""
    published: dict[str, str] = field(default_factory=dict)
    """rl-zoo3's published figure per stock algo (benchmark.md, one run: mean +- std of its episodes)."""


_NORM_OBS_ONLY = "{'norm_obs': True, 'norm_reward': False}"
TASKS: dict[str, Task] = {
    "LunarLander": Task(
        env_id="LunarLanderSplit-v3",
        zoo_id="LunarLander-v3",
        algos=("a2c", "ppo"),
        two_dim={"reward_split": "info", "punishment_gamma": 0.1},
        events="crash",
        published={"a2c": "155.8 +- 80.4 (v2, 200k)", "ppo": "242.1 +- 31.8 (v2, 1M)"},
    ),
    "CliffWalking": Task(
        env_id="CliffWalkingSplit-v1",
        zoo_id="CartPole-v1",
        algos=("a2c", "ppo"),
        two_dim={"reward_split": "info", "punishment_gamma": 0.1},
        variants={"sign": {"reward_split": "sign", "punishment_gamma": 0.99}},
        events="cliff_falls",
        overrides={"n_timesteps": 50_000},
        paths=(13, 15, 17),
    ),
    "LavaGap": Task(
        env_id="LavaGapSplit-v0",
        zoo_id="MiniGrid-KeyCorridorS3R1-v0",
        algos=("ppo",),
        two_dim={"reward_split": "info", "punishment_gamma": 0.1},
        events="lava",
        overrides={"normalize": _NORM_OBS_ONLY},
    ),
    "CartPole": Task(
        env_id="CartPole-v1",
        zoo_id="CartPole-v1",
        algos=("a2c", "ppo"),
        two_dim={"reward_split": "sign"},
        published={"a2c": "500.0 +- 0.0 (500k)", "ppo": "500.0 +- 0.0 (100k)"},
    ),
    "Acrobot": Task(
        env_id="Acrobot-v1",
        zoo_id="Acrobot-v1",
        algos=("a2c", "ppo"),
        two_dim={"reward_split": "sign", "punishment_gamma": 0.99},
        published={"a2c": "-83.4 +- 17.2 (500k)", "ppo": "-73.5 +- 18.2 (1M)"},
    ),
    "Pendulum": Task(
        env_id="Pendulum-v1",
        zoo_id="Pendulum-v1",
        algos=("a2c", "ppo"),
        two_dim={"reward_split": "sign", "punishment_gamma": 0.9},
        published={"a2c": "-163.0 +- 103.2 (1M)", "ppo": "-172.2 +- 104.2 (100k)"},
    ),
}


def task(name: str) -> Task:
    if name not in TASKS:
        raise ValueError(f"env must be one of {sorted(TASKS)}, got {name!r}")
    return TASKS[name]


def split_arm(spec: Task, arm: str) -> tuple[str, str | None]:
    """``(algo, variant)`` of an arm name such as ``ppo``, ``twoda2c`` or ``twoda2c-sign``."""
    algo, _, variant = arm.partition("-")
    stock = STOCK.get(algo, algo)
    if stock not in spec.algos or (variant and (algo not in STOCK or variant not in spec.variants)):
        arms = [*spec.algos, *(a for a, s in STOCK.items() if s in spec.algos)]
        arms += [f"{a}-{v}" for a in arms if a in STOCK for v in spec.variants]
        raise ValueError(f"algos: {arm!r} is not an arm of {spec.env_id}; its arms are {arms}")
    return algo, variant or None


def zoo_entry(spec: Task, arm: str) -> dict[str, Any]:
    """The rl-zoo3 entry of ``arm`` on ``spec``: rl-zoo3's own, the task's overrides, the Monitor keys, the 2D-RL args.

    :raises ValueError: if a 2D-RL arm that reads ``info`` would see rewards that ``VecNormalize`` rescales
        (its ``r_R = reward + info["punishment"]`` would mix two scales)
    """
    import rl_zoo3
    import yaml

    algo, variant = split_arm(spec, arm)
    stock = STOCK.get(algo, algo)
    entries = yaml.safe_load((Path(rl_zoo3.__file__).parent / "hyperparams" / f"{stock}.yml").read_text())
    entry = {**entries[spec.zoo_id], **spec.overrides}
    if spec.events:
        entry["monitor_kwargs"] = f"dict(info_keywords=('{spec.events}',))"
    if algo in STOCK:
        entry.update(spec.variants[variant] if variant else spec.two_dim)
        normalize = entry.get("normalize", False)
        scaled = normalize if isinstance(normalize, bool) else "'norm_reward': False" not in normalize
        if scaled and entry.get("reward_split") in ("info", "cost"):
            raise ValueError(f"env: {spec.env_id}'s entry normalises rewards, which reward_split='info' cannot split")
    return entry


def training_episodes(run_dir: Path, n_envs: int, events: str | None) -> np.ndarray:
    """Every training episode as ``(timestep it ended at, return, punishment events)``, sorted by timestep.

    The Monitor of sub-env ``i`` writes ``<run_dir>/<i>.monitor.csv``; the sub-envs step together,
    so an episode that ends at a sub-env's k-th step ends at timestep ``k * n_envs``.
    """
    rows = []
    for i in range(n_envs):
        with (run_dir / f"{i}.monitor.csv").open() as f:
            next(f)  # the JSON header
            steps = 0
            for record in csv.DictReader(f):
                steps += int(record["l"])
                rows.append((steps * n_envs, float(record["r"]), float(record[events]) if events else 0.0))
    return np.array(sorted(rows), dtype=np.float64).reshape(-1, 3)


def learning_curve(episodes: np.ndarray, n_timesteps: int, bins: int = CURVE_BINS) -> list[list[float]]:
    """Per bin of ``n_timesteps / bins`` steps: ``[end timestep, mean return, events per episode]`` (NaN if empty)."""
    edges = np.linspace(0, n_timesteps, bins + 1)
    index = np.clip(np.searchsorted(edges, episodes[:, 0], side="left") - 1, 0, bins - 1)
    curve = []
    for b in range(bins):
        inside = episodes[index == b]
        mean = inside.mean(axis=0) if len(inside) else np.full(3, math.nan)
        curve.append([float(edges[b + 1]), float(mean[1]), float(mean[2])])
    return curve


def evaluate(model: Any, env: Any, episodes: int, events: str | None) -> dict[str, float]:
    """Mean return, length and punishment events of ``episodes`` deterministic episodes, and the share with an event."""
    results: list[tuple[float, int, float]] = []
    obs = env.reset()
    total, length = 0.0, 0
    while len(results) < episodes:
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, done, info = env.step(action)
        total, length = total + float(reward[0]), length + 1
        if done[0]:
            results.append((total, length, float(info[0].get(events, 0.0)) if events else 0.0))
            total, length = 0.0, 0
    r, n, e = (np.array(x) for x in zip(*results, strict=True))
    return {
        "final_return": float(r.mean()),
        "final_return_std": float(r.std()),
        "final_length": float(n.mean()),
        "final_events": float(e.mean()),
        "final_event_share": float(np.mean(e > 0)),
    }


def train_and_evaluate(task_name: str, arm: str, seed: int, out: str, episodes: int, n_timesteps: int | None) -> Row:
    """Train ``arm`` on ``task_name`` with rl-zoo3 (seed ``seed``, logs in ``out/<arm>_seed<seed>``); its row."""
    import torch as th
    import yaml
    from rl_zoo3.train import train
    from rl_zoo3.utils import get_wrapper_class
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    from sb3_twodrl.zoo import prepare_zoo_argv, run_zoo_entry
    from twodrl_bench.algos import algo_class

    th.set_num_threads(1)
    clock = time.perf_counter()
    spec = task(task_name)
    algo, _ = split_arm(spec, arm)
    entry = zoo_entry(spec, arm)
    log = Path(out) / f"{arm}_seed{seed}"
    shutil.rmtree(log, ignore_errors=True)  # what an interrupted attempt left
    log.mkdir(parents=True)
    conf = log / f"{algo}.yml"
    conf.write_text(yaml.safe_dump({spec.env_id: entry}))
    argv = ["--algo", algo, "--env", spec.env_id, "--seed", str(seed), "-f", str(log), "--eval-freq", "-1"]
    argv += ["--vec-env", "dummy", "--log-interval", "-1", "--device", "cpu", "--conf-file", str(conf)]
    if n_timesteps is not None:
        argv += ["--n-timesteps", str(n_timesteps)]
    run_zoo_entry("train.py", prepare_zoo_argv(argv), train)
    (run,) = sorted((log / algo).glob(f"{spec.env_id}_*"))
    budget = int(n_timesteps or entry["n_timesteps"])
    train_eps = training_episodes(run, int(entry.get("n_envs", 1)), spec.events)
    model = algo_class(algo).load(run / f"{spec.env_id}.zip", device="cpu")
    env = make_vec_env(spec.env_id, n_envs=1, seed=EVAL_SEED + seed, wrapper_class=get_wrapper_class(entry))
    stats = run / spec.env_id / "vecnormalize.pkl"
    if stats.exists():
        env = VecNormalize.load(str(stats), env)
        env.training, env.norm_reward = False, False
    final = evaluate(model, env, episodes, spec.events)
    env.close()
    curve = learning_curve(train_eps, budget)
    (log / "curve.json").write_text(json.dumps(curve))
    return {
        "task": task_name,
        "env": spec.env_id,
        "arm": arm,
        "seed": seed,
        "n_timesteps": budget,
        **final,
        "train_episodes": len(train_eps),
        "train_return": float(train_eps[:, 1].mean()) if len(train_eps) else math.nan,
        "train_events_per_episode": float(train_eps[:, 2].mean()) if len(train_eps) else math.nan,
        "train_event_share": float(np.mean(train_eps[:, 2] > 0)) if len(train_eps) else math.nan,
        "curve": curve,
        "wall_s": round(time.perf_counter() - clock, 1),
    }


def _cell(values: Sequence[float], digits: int = 1) -> str:
    mean, half, n = mean_ci(values)
    if n == 0:
        return "-"
    if not math.isfinite(half) or half == 0:
        return f"{mean:.{digits}f} (n={n})"
    return f"{mean:.{digits}f} [{mean - half:.{digits}f}, {mean + half:.{digits}f}] (n={n})"


def _diff(a: Sequence[float], b: Sequence[float], digits: int = 1) -> str:
    if len(a) < 2 or len(b) < 2:
        return "-"
    d, h = welch_ci(a, b)
    if not math.isfinite(h):
        h = 0.0
    return f"{d:+.{digits}f} [{d - h:+.{digits}f}, {d + h:+.{digits}f}]"


MIN_SEEDS_FOR_VERDICT = 5


def verdict(ret_2d: Sequence[float], ret_st: Sequence[float], ev_2d: Sequence[float], ev_st: Sequence[float]) -> str:
    """The pre-registered rule (docs/benchmark.md): Welch intervals of 2D - stock on the final return and the events.

    Events are left out where both are empty (a task without punishment events).
    """
    if min(len(ret_2d), len(ret_st)) < MIN_SEEDS_FOR_VERDICT:
        return f"no verdict (< {MIN_SEEDS_FOR_VERDICT} seeds)"

    def interval(a: Sequence[float], b: Sequence[float]) -> tuple[float, float]:
        d, h = welch_ci(a, b)
        return (d, d) if not math.isfinite(h) else (d - h, d + h)

    ret_lo, ret_hi = interval(ret_2d, ret_st)
    ev_lo, ev_hi = interval(ev_2d, ev_st) if ev_2d and all(map(math.isfinite, [*ev_2d, *ev_st])) else (0.0, 0.0)
    helps = ret_lo > 0 or (ev_hi < 0 and not ret_hi < 0)
    hurts = ret_hi < 0 or ev_lo > 0
    if helps and hurts:
        return "trade-off"
    return "helps" if helps else "hurts" if hurts else "no difference shown"


def table(task_name: str, rows: Sequence[Row]) -> str:
    """Markdown: per 2D-RL arm against its stock arm, final return and training punishment events, with 95% intervals.

    Means over seeds with t-intervals, differences (2D - stock) with Welch intervals, over the seeds both have.
    """
    spec = task(task_name)
    by_arm: dict[str, dict[int, Row]] = {}
    for row in rows:
        by_arm.setdefault(row["arm"], {})[row["seed"]] = row
    head = "| task | budget | stock arm | return | 2D-RL arm | return | 2D - stock [95% Welch] |"
    head += " training events/episode, stock | 2D | 2D - stock | verdict | rl-zoo3 published (v2 where marked) |"
    lines = [head, "|" + "---|" * 12]
    for arm in sorted(by_arm):
        algo, _ = split_arm(spec, arm)
        stock = STOCK.get(algo)
        if stock is None or stock not in by_arm:
            continue
        seeds = sorted(by_arm[arm].keys() & by_arm[stock].keys())
        two = [by_arm[arm][s] for s in seeds]
        base = [by_arm[stock][s] for s in seeds]
        ret_2d, ret_st = [r["final_return"] for r in two], [r["final_return"] for r in base]
        ev_2d, ev_st = [r["train_events_per_episode"] for r in two], [r["train_events_per_episode"] for r in base]
        events = f"{_cell(ev_st, 3)} | {_cell(ev_2d, 3)} | {_diff(ev_2d, ev_st, 3)}" if spec.events else "- | - | -"
        budget = f"{base[0]['n_timesteps']:,}" if base else "-"
        lines.append(
            f"| {task_name} | {budget} | {stock} | {_cell(ret_st)} | {arm} | {_cell(ret_2d)} | {_diff(ret_2d, ret_st)} "
            f"| {events} | {verdict(ret_2d, ret_st, ev_2d if spec.events else [], ev_st)} "
            f"| {spec.published.get(stock, '-')} |"
        )
    if spec.paths:
        lines += ["", path_table(spec, by_arm)]
    return "\n".join(lines)


def path_table(spec: Task, by_arm: dict[str, dict[int, Row]]) -> str:
    """Per arm, the share of seeds whose final deterministic episodes take each path (event-free, that length)."""
    names = [f"{n}-step path" for n in spec.paths]
    lines = [f"| arm | {' | '.join(names)} | other (timeout, fall, mixed) |", "|" + "---|" * (len(names) + 2)]
    for arm, seeds in sorted(by_arm.items()):
        rows = list(seeds.values())
        counts = [sum(r["final_length"] == n and r["final_events"] == 0 for r in rows) for n in spec.paths]
        cells = [*counts, len(rows) - sum(counts)]
        text = [f"{k}/{len(rows)} [{lo:.2f}, {hi:.2f}]" for k in cells for lo, hi in [wilson(k, len(rows))]]
        lines.append(f"| {arm} | {' | '.join(text)} |")
    return "\n".join(lines)


def figure(task_name: str, rows: Sequence[Row], path: Path) -> None:
    """Learning curves: per arm the mean training return per bin over seeds, with its 95% t-interval."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for arm in sorted({r["arm"] for r in rows}):
        curves = np.array([r["curve"] for r in rows if r["arm"] == arm])  # seeds x bins x 3
        stats = [mean_ci(curves[:, b, 1]) for b in range(curves.shape[1])]
        x = curves[0, :, 0]
        mean = np.array([m for m, _, _ in stats])
        half = np.nan_to_num(np.array([h for _, h, _ in stats]))
        ax.plot(x, mean, label=f"{arm} (n={len(curves)})")
        ax.fill_between(x, mean - half, mean + half, alpha=0.2)
    ax.set_xlabel("timesteps")
    ax.set_ylabel("training episode return")
    ax.set_title(f"{task_name} ({task(task_name).env_id})")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_rows_csv(rows: Sequence[Row], path: Path) -> None:
    """The rows without their curves, sorted by arm and seed."""
    keys = [k for k in rows[0] if k != "curve"]
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(sorted(rows, key=lambda r: (r["arm"], r["seed"])))


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", required=True, help=f"task: one of {sorted(TASKS)}")
    p.add_argument("--algos", nargs="+", help="arms (default: every stock algo of the task and its 2D-RL arm)")
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    p.add_argument("--episodes", type=int, default=20, help="deterministic evaluation episodes per final model")
    p.add_argument("--n-timesteps", type=int, help="training budget (default: the task's rl-zoo3 entry)")
    p.add_argument("--out", type=Path, default=Path("results") / "benchmark")
    p.add_argument("--workers", type=int, default=1, help="worker processes (0: train in this process)")
    p.add_argument("--no-figure", action="store_true", help="skip the learning-curve figure (no matplotlib)")
    args = p.parse_args(argv)
    spec = task(args.env)
    if args.algos is None:
        args.algos = [a for s in spec.algos for a in (s, *(k for k, v in STOCK.items() if v == s))]
    for arm in args.algos:
        split_arm(spec, arm)
    if len(args.seeds) < 2:
        raise ValueError(f"seeds: an interval needs at least 2, got {args.seeds!r}")
    if args.episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {args.episodes}")
    if args.n_timesteps is not None and args.n_timesteps < 1:
        raise ValueError(f"n_timesteps must be >= 1, got {args.n_timesteps}")
    if args.workers < 0:
        raise ValueError(f"workers must be >= 0, got {args.workers}")
    return args


def settings(args: argparse.Namespace) -> dict[str, str]:
    """What a kept row must agree on, per arm: its rl-zoo3 entry, the budget, the evaluation episodes."""
    spec = task(args.env)
    kept = {"n_timesteps": args.n_timesteps, "episodes": args.episodes}
    return {a: json.dumps({"entry": zoo_entry(spec, a), **kept}, sort_keys=True, default=str) for a in args.algos}


def _run(
    todo: list[tuple[str, int]], task_name: str, runs: str, episodes: int, n_timesteps: int | None, workers: int
) -> Iterator[tuple[str, int, Row]]:
    """``(arm, seed, row)`` of every job as it finishes: in this process (``workers=0``) or in a spawned pool."""
    if workers == 0 or not todo:
        for arm, seed in todo:
            yield arm, seed, train_and_evaluate(task_name, arm, seed, runs, episodes, n_timesteps)
        return
    with cf.ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as pool:
        jobs = {pool.submit(train_and_evaluate, task_name, a, s, runs, episodes, n_timesteps): (a, s) for a, s in todo}
        for job in cf.as_completed(jobs):
            yield (*jobs[job], job.result())


def benchmark(argv: list[str] | None = None) -> list[Row]:
    """Run (or resume) the arms' seeds of a task; write rows (JSON, CSV), the table and the figure; the rows."""
    args = parse_args(argv)
    out = args.out / args.env
    store, done = open_record(out, settings(args), "rows.json")
    todo = [(a, s) for s in args.seeds for a in args.algos if f"{a}_seed{s}" not in done]
    runs = str(out / "runs")
    for arm, seed, row in _run(todo, args.env, runs, args.episodes, args.n_timesteps, args.workers):
        done[f"{arm}_seed{seed}"] = row
        atomic_write_bytes(store, json.dumps(done, indent=1, sort_keys=True).encode())  # a kill keeps the old file
        print(f"{arm} seed {seed}: return {row['final_return']:.1f} ({row['wall_s']:.0f} s)", flush=True)
    rows = [done[f"{a}_seed{s}"] for a in args.algos for s in args.seeds]
    write_rows_csv(list(done.values()), out / "rows.csv")
    text = table(args.env, list(done.values()))
    (out / "table.md").write_text(text + "\n")
    if not args.no_figure:
        figure(args.env, list(done.values()), out / "curve.png")
    print(text)
    return rows


def main(argv: list[str] | None = None) -> None:
    benchmark(argv)
