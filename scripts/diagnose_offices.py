"""Why some development offices fail (issue 64 part 1, issue 66 part 2): figures and a summary of measured numbers.

Development offices only (generated map seeds 0-99). Five stages, each writes its numbers as JSON into ``--out``;
``summary.md`` is written from every stage's JSON found there, so stages can run one at a time:

* ``checks`` (``goal_checks.png``): the goal checks over training (goal rate and mean return against steps) of the
  TwoDimA2C runs that failed or learned late without the progress signal (``results/reliability``) next to the
  runs of the same map and seed with it (``results/every_office``; where it has none yet, a run folder given with
  ``--after-run``);
* ``paths`` (``paths.png``, ``basins.png``): the deterministic policy's path from the map's start (``--policy
  LABEL ALGO MAP ZIP``) on the map's walls with its collision or loop, the outcome from every training start
  cell (the goal's basin), the stochastic policy's goal rate; with ``--run``, the basin at each ``--save-freq``
  checkpoint of a run folder;
* ``robot`` (``robot_paths.png``): a policy trained on a database (``--robot-policy LABEL ALGO MAP DATABASE ZIP``):
  its deterministic path on the database env from the start, with its moves that clear the walls by less than
  5 cm, and its 20 trials on the stand-in robot ``NomadOfficeReal-v0`` from there;
* ``database`` (``database_readings.png``): per office (``--db-maps``), a database recorded as documented (8
  readings a cell, the stand-in robot's model, seed 0, cached in ``--cache``): the per-cell spread of the readings,
  their aliasing, the recording's odometry error and bumped drives; and the stand-in robot ``NomadOfficeReal-v0``
  driven 20 times from the start, open loop, along two shortest lattice paths (breadth-first search's and the one
  that clears the walls the most): its goal rate, drift, and the gap between its readings and the database's;
* ``settings``: the starts, time limit and derived settings of every office above, the runs' outcomes, and the
  rank correlation of each task fact with the steps to learn.

    python scripts/diagnose_offices.py --out results/every_office/diagnosis --stages checks settings
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import twodrl_envs  # noqa: F401  (registers the env IDs)
from sb3_twodrl.callbacks import SUCCESS_THRESHOLD
from twodrl_envs.memorable.database import SensorDatabase, load_database, save_database
from twodrl_envs.memorable.recording import record_database, shortest_paths
from twodrl_envs.nomad.core import OfficeCore, office_core
from twodrl_envs.nomad.geometry import ROBOT_RADIUS_CM, swept_clearance
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import IR_MAX_CM, N_SONAR
from twodrl_zoo.hyperparams import derived_settings, task_facts
from twodrl_zoo.recipe import size_class

STAGES = ("checks", "paths", "robot", "database", "settings")
LATE = 0.5
"""A run "learned late" when it stopped as learned after more than this share of its budget."""
INTO_GOAL = 10
"""Moves the robot's drives go on towards the goal region's centre past the shortest path's first goal cell."""
TIGHT_CM = 5.0
"""A move of the shortest path is tight when its swept disc clears the walls by less than this."""
FAR_CM = 50.0
"""A reading is aliased to a far cell when its nearest cell mean lies farther than this from its own cell."""
TRIALS = 20
K = 8
DPI = 100


def dev_map(value: str) -> str:
    """``value`` if it names a development office ``generated:S|M|L:SEED`` with SEED 0-99, else ``ValueError``."""
    parts = value.split(":")
    if len(parts) != 3 or parts[0] != "generated" or parts[1] not in ("S", "M", "L") or not parts[2].isdigit():
        raise argparse.ArgumentTypeError(f"map must be generated:S|M|L:SEED, got {value!r}")
    if not 0 <= int(parts[2]) <= 99:
        raise argparse.ArgumentTypeError(f"map seed must be a development seed 0-99, got {value!r}")
    return value


def short(map_name: str) -> str:
    """``generated:M:2`` as ``M2``."""
    _, size, seed = map_name.split(":")
    return f"{size}{seed}"


# --- goal checks -------------------------------------------------------------------------------------------------


def read_jsonl(paths: list[Path]) -> list[dict[str, Any]]:
    return [json.loads(line) | {"file": str(p)} for p in paths for line in p.read_text().splitlines() if line.strip()]


def read_rows(paths: list[Path]) -> list[dict[str, str]]:
    rows = []
    for path in paths:
        with path.open() as f:
            rows += [row | {"file": str(path)} for row in csv.DictReader(f)]
    return rows


def chosen_runs(rows: list[dict[str, str]], algo: str) -> list[tuple[str, int, str]]:
    """``(map, seed, why)`` of the ``algo`` rows that failed (goal rate < 0.8) or learned late (:data:`LATE`), in the
    first file's order of the reliability part A rows (``dev_rows_a/b``)."""
    chosen: dict[tuple[str, int], str] = {}
    for row in rows:
        if row["algo"] != algo or "_2x" in row["file"]:
            continue
        key = (row["map"], int(row["seed"]))
        if float(row["goal_rate"]) < SUCCESS_THRESHOLD:
            chosen[key] = f"failed in budget {int(row['budget']):,}"
        elif int(row["steps"]) > LATE * int(row["budget"]):
            chosen[key] = f"learned late ({int(row['steps']):,} of {int(row['budget']):,})"
    for row in rows:  # the continued runs to the ceiling 2B
        key = (row["map"], int(row["seed"]))
        if row["algo"] == algo and "_2x" in row["file"] and key in chosen:
            result = f"learned at {int(row['steps']):,}" if row["learned"] == "True" else "failed"
            chosen[key] = f"{chosen[key].split(';')[0]}; to 2B: {result}"
    return [(m, s, why) for (m, s), why in chosen.items()]


def longest(records: list[dict[str, Any]], map_name: str, seed: int, algo: str) -> dict[str, Any] | None:
    """The record of ``map_name``/``seed``/``algo`` with the most checks (the continued run where there is one)."""
    same = [r for r in records if r["map"] == map_name and int(r["seed"]) == seed and r["algo"] == algo]
    return max(same, key=lambda r: len(r["checks"]), default=None)


def run_folder_record(label: str, folder: Path) -> dict[str, Any]:
    """A run folder's ``goal_checks.json`` (the train command's) as a checks record; ``label`` is ``MAP:SEED``."""
    map_name, seed = label.rsplit(":", 1)
    record = json.loads((folder / "goal_checks.json").read_text())
    return record | {"map": dev_map(map_name), "seed": int(seed), "algo": "twoda2c", "file": str(folder)}


def stage_checks(args: argparse.Namespace, plt: Any) -> dict[str, Any]:
    rows = read_rows(args.before_rows)
    before = read_jsonl(args.before)
    after = read_jsonl(args.after)
    own = [run_folder_record(label, Path(f)) for label, f in args.after_run]
    runs = chosen_runs(rows, "twoda2c")
    budgets = {(r["map"], int(r["seed"])): int(r["budget"]) for r in rows if "_2x" not in r["file"]}
    n_rows = (len(runs) + 1) // 2
    fig, axes = plt.subplots(n_rows, 4, figsize=(15, 1.5 * n_rows + 0.9), sharex=True, squeeze=False)
    summary = []
    for i, (map_name, seed, why) in enumerate(runs):
        ax_rate, ax_return = axes[i // 2, 2 * (i % 2)], axes[i // 2, 2 * (i % 2) + 1]
        entry: dict[str, Any] = {"map": map_name, "seed": seed, "why": why}
        for name, record, style in (
            ("no progress", longest(before, map_name, seed, "twoda2c"), "C3"),
            (
                "progress 0.05",
                longest(after, map_name, seed, "twoda2c") or longest(own, map_name, seed, "twoda2c"),
                "C0",
            ),
        ):
            if record is None:
                continue
            at = np.array([int(c["timesteps"]) for c in record["checks"]])
            steps = at / 1e6
            rates = np.array([c["goal_rate"] for c in record["checks"]])
            returns = np.array([c["mean_return"] for c in record["checks"]])
            ax_rate.plot(steps, rates, "-", color=style, lw=1.2, label=name)
            ax_return.plot(steps, returns, "-", color=style, lw=1.0, label=name)
            passed = np.flatnonzero(rates >= SUCCESS_THRESHOLD)
            entry[name] = {
                "source": record["file"],
                "checks": len(rates),
                "last_step": int(at[-1]),
                "first_pass": None if len(passed) == 0 else int(at[passed[0]]),
                "learned_at": record.get("learned_at"),
                "relapses": int(np.sum(rates[passed[0] :] < SUCCESS_THRESHOLD)) if len(passed) else None,
                "time_limit_checks": int(np.sum((rates == 0.0) & (returns < -2.0))),
                "collision_checks": int(np.sum((rates == 0.0) & (returns >= -2.0))),
            }
        summary.append(entry)
        for ax in (ax_rate, ax_return):
            ax.axvline(budgets[(map_name, seed)] / 1e6, color="0.5", ls=":", lw=1)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        ax_rate.set_ylabel(f"{short(map_name)} seed {seed}\ngoal rate", fontsize=8)
        ax_rate.set_ylim(-0.05, 1.05)
        ax_return.set_ylabel("mean return", fontsize=8)
        ax_rate.set_title(why, fontsize=7, loc="left")
    for ax in axes[-1]:
        ax.set_xlabel("training steps (millions)", fontsize=8)
    if len(runs) % 2:
        axes[-1, 2].set_axis_off()
        axes[-1, 3].set_axis_off()
    axes[0, 0].legend(fontsize=7, loc="center right")
    fig.suptitle(
        "Goal checks from the map's start, TwoDimA2C, development M offices: without the progress signal "
        "(results/reliability) and with it (progress 0.05); dotted: the budget B\nreturn about -3: the time limit "
        "reached (300 moves x 0.01, the signal adds to it); about -1: a collision",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.96 if n_rows > 3 else 0.9))
    fig.savefig(args.out / "goal_checks.png", dpi=DPI)
    plt.close(fig)
    return {"runs": summary, "late_share": LATE}


# --- deterministic paths -----------------------------------------------------------------------------------------


def episode(env: gym.Env, model: Any, deterministic: bool, seed: int) -> tuple[np.ndarray, bool, bool]:
    """One episode of ``model`` from the env's start: the positions ``(moves + 1, 2)``, collided, reached the goal."""
    obs, info = env.reset(seed=seed)
    positions, collided, goal, truncated = [info["position_cm"]], False, False, False
    while not (collided or goal or truncated):
        action, _ = model.predict(obs, deterministic=deterministic)
        obs, _, _, truncated, info = env.step(int(action))
        positions.append(info["position_cm"])
        collided, goal = bool(info["collision"]), bool(info["is_success"])
    return np.array(positions), collided, goal


def rollout(model: Any, map_name: str) -> dict[str, Any]:
    """The deterministic path of ``model`` from the map's start on ``NomadOffice-v0`` with the task's test options,
    and the goal rate of the stochastic policy from there (:data:`TRIALS` episodes)."""
    derived = derived_settings("NomadOffice-v0", {"map": map_name})
    test = {} if derived is None else derived.eval_env_kwargs
    env = gym.make("NomadOffice-v0", map=map_name, **test)
    xy, collided, goal = episode(env, model, True, 0)
    model.set_random_seed(0)
    stochastic = [episode(env, model, False, seed) for seed in range(TRIALS)]
    env.close()
    first: dict[tuple[float, float], int] = {}
    loop_start = loop_period = None
    moved = xy[:-1] if collided else xy  # a collision leaves the robot where it was: no loop
    for step, pos in enumerate(map(tuple, moved)):
        if pos in first:  # on the lattice the policy's action is a function of the cell: a repeat is a cycle
            loop_start, loop_period = first[pos], step - first[pos]
            break
        first[pos] = step
    return {
        "map": map_name,
        "moves": len(xy) - 1,
        "outcome": "goal" if goal else "collision" if collided else "time limit",
        "time_limit": test.get("max_episode_steps"),
        "loop_start": loop_start,
        "loop_period": loop_period,
        "stochastic_goal_rate": float(np.mean([g for _, _, g in stochastic])),
        "stochastic_median_moves": median_or_none(np.array([len(p) - 1 for p, _, g in stochastic if g])),
        "positions": xy.tolist(),
    }


def draw_office(ax: Any, core: OfficeCore) -> None:
    from matplotlib.patches import Rectangle

    for wall in core.office.walls:
        ax.plot(wall[[0, 2]], wall[[1, 3]], "k-", lw=1.2)
    x0, y0, x1, y1 = core.office.regions["goal"]
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color="C2", alpha=0.3, label="goal"))
    ax.plot(*core.office.start, "o", color="C2", ms=6, mec="k", label="start")
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def move_slack(core: OfficeCore, cells: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """How far (cm) the robot's swept disc clears the walls on the moves ``cells -> targets`` (lattice indices)."""
    xy = core.lattice.cells
    return swept_clearance(xy[cells], xy[targets], core.office.walls) - ROBOT_RADIUS_CM


def shortest_to_goal(core: OfficeCore, into_goal: int = 0, widest: bool = False) -> np.ndarray:
    """The cell centres ``(n, 2)`` of a shortest lattice path from the start to the goal: breadth-first search's
    (:func:`~twodrl_envs.memorable.recording.shortest_paths`, the recorder's), or with ``widest`` the shortest path
    whose tightest move clears the walls the most; continued by up to ``into_goal`` moves towards the goal region's
    centre (so that a drifting robot following it enters the region)."""
    paths = shortest_paths(core)
    length = np.array([len(p) if core.lattice.reachable[c] else -1 for c, p in enumerate(paths)])
    goal_cells = np.flatnonzero(core.goal & core.lattice.reachable)
    nearest = goal_cells[length[goal_cells] == length[goal_cells].min()]
    moves = core.lattice.moves
    if widest:
        width = np.full(len(moves), -np.inf)
        parent = np.full(len(moves), -1)
        width[core.start_cell] = np.inf
        for k in range(int(length[nearest[0]])):
            layer = np.flatnonzero(length == k)
            for action in range(4):
                target = moves[layer, action]
                ok = target >= 0
                src, dst = layer[ok], target[ok]
                ok = length[dst] == k + 1
                src, dst = src[ok], dst[ok]
                value = np.minimum(width[src], move_slack(core, src, dst))
                for a_cell, b_cell, v in zip(src, dst, value, strict=True):
                    if v > width[b_cell]:
                        width[b_cell], parent[b_cell] = v, a_cell
        cells = [int(nearest[np.argmax(width[nearest])])]
        while cells[-1] != core.start_cell:
            cells.append(int(parent[cells[-1]]))
        cells = cells[::-1]
    else:
        cells = [core.start_cell]
        for action in paths[int(nearest[0])]:
            cells.append(int(moves[cells[-1], action]))
    x0, y0, x1, y1 = core.office.regions["goal"]
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    for _ in range(into_goal):
        options = moves[cells[-1]][moves[cells[-1]] >= 0]
        distance = np.linalg.norm(core.lattice.cells[options] - centre, axis=1)
        if distance.min() >= np.linalg.norm(core.lattice.cells[cells[-1]] - centre):
            break
        cells.append(int(options[np.argmin(distance)]))
    return core.lattice.cells[cells]


OUTCOMES = ("goal", "collision", "time limit")
FIELD_COLOURS = ("#9bd49b", "#f4a3a3", "#f8c77e")


def policy_field(model: Any, map_name: str, limit: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the deterministic policy leads from every training start cell of ``NomadOffice-v0`` on ``map_name``:
    the cells ``(n,)``, their outcome ``(n,)`` (index into :data:`OUTCOMES`) within ``limit`` moves, followed on
    the lattice's move table (the ideal robot's moves are the table's), and the policy's probability of its most
    likely action there ``(n,)``."""
    import torch

    env = gym.make("NomadOffice-v0", map=map_name)
    core = office_core(map_name)
    robot = env.unwrapped.robot  # type: ignore[attr-defined]
    reachable = np.flatnonzero(core.lattice.reachable & ~core.goal)
    obs = np.stack([env.reset(options={"position": tuple(core.lattice.cells[c])})[0] for c in reachable])
    env.close()
    actions = np.full(len(core.lattice.cells), -1)
    actions[reachable] = model.predict(obs, deterministic=True)[0]
    top = np.zeros(len(core.lattice.cells))
    with torch.no_grad():
        probs = model.policy.get_distribution(model.policy.obs_to_tensor(obs)[0]).distribution.probs
    top[reachable] = probs.max(dim=1).values.numpy()
    starts = robot.start_cells
    cell = starts.copy()
    outcome = np.full(len(starts), 2)
    running = np.ones(len(starts), dtype=bool)
    for _ in range(limit):
        nxt = core.lattice.moves[cell[running], actions[cell[running]]]
        rows = np.flatnonzero(running)
        outcome[rows[nxt < 0]] = 1
        reached = nxt >= 0
        outcome[rows[reached][core.goal[nxt[reached]]]] = 0
        cell[rows[reached]] = nxt[reached]
        running[rows] = reached & ~core.goal[np.maximum(nxt, 0)]
        if not running.any():
            break
    return starts, outcome, top[starts]


def median_or_none(values: np.ndarray) -> float | None:
    return float(np.median(values)) if len(values) else None


def stage_paths(args: argparse.Namespace, plt: Any) -> dict[str, Any]:
    return {"policies": policy_paths(args, plt), "runs": stage_basins(args, plt) if args.run else []}


def policy_paths(args: argparse.Namespace, plt: Any) -> list[dict[str, Any]]:
    from sb3_twodrl import ALGOS

    results = []
    cols = min(2, len(args.policy))
    rows = (len(args.policy) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.6 * cols, 5.6 * rows), squeeze=False)
    for ax in axes.ravel()[len(args.policy) :]:
        ax.set_axis_off()
    for (label, algo, map_name, zip_path), ax in zip(args.policy, axes.ravel(), strict=False):
        if algo not in ALGOS:
            raise SystemExit(f"--policy: algo must be one of {sorted(ALGOS)}, got {algo!r}")
        model = ALGOS[algo].load(zip_path, device="cpu")
        path = rollout(model, dev_map(map_name))
        core = office_core(map_name)
        starts, outcome, top = policy_field(model, map_name, int(path["time_limit"] or 300))
        robot = gym.make("NomadOffice-v0", map=map_name).unwrapped.robot  # type: ignore[attr-defined]
        far = robot.goal_distance[starts] >= robot.goal_distance[core.start_cell]
        xy = core.lattice.cells[starts]
        for k, (name, colour) in enumerate(zip(OUTCOMES, FIELD_COLOURS, strict=True)):
            ax.scatter(*xy[outcome == k].T, s=6, marker="s", color=colour, lw=0)
            ax.plot([], [], "s", color=colour, ms=5, label=f"from here: {name}")
        draw_office(ax, core)
        best = shortest_to_goal(core)
        ax.plot(best[:, 0], best[:, 1], "--", color="0.35", lw=1, label=f"shortest path ({len(best) - 1} moves)")
        xy = np.array(path["positions"])
        ax.plot(xy[:, 0], xy[:, 1], "-", color="C0", lw=1.8, label="path from the start")
        if path["loop_start"] is not None:
            loop = xy[path["loop_start"] : path["loop_start"] + path["loop_period"] + 1]
            ax.plot(loop[:, 0], loop[:, 1], "-", color="C1", lw=4, alpha=0.9, label=f"loop of {path['loop_period']}")
        if path["outcome"] == "collision":
            ax.plot(*xy[-1], "X", color="C3", ms=9, mec="k", label="collision")
        shares = {name: float(np.mean(outcome == k)) for k, name in enumerate(OUTCOMES)}
        ax.set_title(
            f"{label}\n{short(map_name)} from the start: {path['outcome']} after {path['moves']} moves"
            + ("" if path["loop_start"] is None else f", looping from move {path['loop_start']}")
            + f"\nfrom all start cells: goal {shares['goal']:.0%}, collision {shares['collision']:.0%}, "
            f"time limit {shares['time limit']:.0%}",
            fontsize=8,
        )
        ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3, frameon=False)
        results.append(
            {"label": label, "algo": algo, "policy": zip_path}
            | {k: v for k, v in path.items() if k != "positions"}
            | {f"cells_{name.replace(' ', '_')}": share for name, share in shares.items()}
            | {"cells_as_far_goal": float(np.mean(outcome[far] == 0))}
            | {
                f"top_prob_{name.replace(' ', '_')}": median_or_none(top[outcome == k])
                for k, name in enumerate(OUTCOMES)
            }
        )
    fig.tight_layout()
    fig.savefig(args.out / "paths.png", dpi=DPI)
    plt.close(fig)
    return results


def checkpoints(folder: Path) -> list[tuple[int, Path]]:
    """The ``--save-freq`` checkpoints ``rl_model_<steps>_steps.zip`` of a run folder, by steps."""
    found = [(int(p.stem.split("_")[2]), p) for p in folder.glob("rl_model_*_steps.zip")]
    if not found:
        raise SystemExit(f"--run: no rl_model_*_steps.zip in {folder} (train with --save-freq)")
    return sorted(found)


def stage_basins(args: argparse.Namespace, plt: Any) -> list[dict[str, Any]]:
    """Over training (``--run``'s checkpoints): the share of training start cells from which the deterministic
    policy reaches the goal, and the outcome from the map's start."""
    from sb3_twodrl import ALGOS

    runs = []
    fig, ax = plt.subplots(figsize=(9.5, 3.8))
    for (label, algo, map_name, folder), colour in zip(args.run, ("C3", "C0", "C1", "C2", "C4"), strict=False):
        core = office_core(dev_map(map_name))
        robot = gym.make("NomadOffice-v0", map=map_name).unwrapped.robot  # type: ignore[attr-defined]
        points = []
        for steps, path in checkpoints(Path(folder)):
            model = ALGOS[algo].load(path, device="cpu")
            start = rollout(model, map_name)
            starts, outcome, _ = policy_field(model, map_name, int(start["time_limit"] or 300))
            far = robot.goal_distance[starts] >= robot.goal_distance[core.start_cell]
            points.append(
                {
                    "steps": steps,
                    "cells_goal": float(np.mean(outcome == 0)),
                    "cells_as_far_goal": float(np.mean(outcome[far] == 0)),
                    "from_start": start["outcome"],
                }
            )
        x = np.array([p["steps"] for p in points]) / 1e6
        ax.plot(x, [p["cells_goal"] for p in points], "o-", color=colour, label=f"{label}: all start cells")
        ax.plot(x, [p["cells_as_far_goal"] for p in points], "s--", color=colour, label=f"{label}: as far as the start")
        runs.append({"label": label, "map": map_name, "folder": str(folder), "points": points})
    ax.set(xlabel="training steps (millions)", ylabel="share reaching the goal", ylim=(-0.02, 1.02))
    ax.set_title("Cells from which the deterministic policy reaches the goal", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    fig.savefig(args.out / "basins.png", dpi=DPI)
    plt.close(fig)
    return runs


def stage_robot(args: argparse.Namespace, plt: Any) -> dict[str, Any]:
    """A database-trained policy (``--robot-policy``): its deterministic path on its database env from the start
    (the lattice path it learned, with its tight moves) and :data:`TRIALS` trials on the stand-in robot from there."""
    from sb3_twodrl import ALGOS

    results = []
    fig, axes = plt.subplots(1, len(args.robot_policy), figsize=(6 * len(args.robot_policy), 5.6), squeeze=False)
    for (label, algo, map_name, database, zip_path), ax in zip(args.robot_policy, axes[0], strict=True):
        model = ALGOS[algo].load(zip_path, device="cpu")
        core = office_core(dev_map(map_name))
        derived = derived_settings("NomadOfficeMemorable-v0", {"map": map_name, "database": database})
        test = {} if derived is None else derived.eval_env_kwargs
        env = gym.make("NomadOfficeMemorable-v0", map=map_name, database=database, **test)
        lattice, collided, goal = episode(env, model, True, 0)
        env.close()
        cells = np.array([core.lattice.index(xy) for xy in lattice])
        slack = move_slack(core, cells[:-1], cells[1:]) if len(cells) > 1 else np.zeros(0)
        robot = gym.make("NomadOfficeReal-v0", map=map_name, **test)
        trials = [episode(robot, model, True, trial) for trial in range(TRIALS)]
        robot.close()
        draw_office(ax, core)
        for k, (xy, hit, _) in enumerate(trials):
            ax.plot(xy[:, 0], xy[:, 1], "-", color="0.45", lw=0.6, alpha=0.7, label="robot trials" if k == 0 else None)
            if hit:
                ax.plot(*xy[-1], "X", color="C3", ms=6, mec="k", mew=0.4)
        ax.plot([], [], "X", color="C3", ms=6, mec="k", mew=0.4, label="robot collision")
        ax.plot(lattice[:, 0], lattice[:, 1], "-", color="C0", lw=1.6, label="its path on the database")
        tight = lattice[1:][slack < TIGHT_CM]
        ax.plot(tight[:, 0], tight[:, 1], "o", color="C1", ms=4, label=f"moves clearing walls by < {TIGHT_CM:.0f} cm")
        goals = sum(g for _, _, g in trials)
        hits = [len(xy) - 1 for xy, hit, _ in trials if hit]
        outcome = "goal" if goal else "collision" if collided else "time limit"
        ax.set_title(
            f"{label}\n{short(map_name)} on its database: {outcome}"
            f" in {len(lattice) - 1} moves, {int(np.sum(slack < TIGHT_CM))} tight; stand-in robot: goal {goals} of "
            f"{TRIALS}, {len(hits)} collisions",
            fontsize=8,
        )
        ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2, frameon=False)
        results.append(
            {
                "label": label,
                "map": map_name,
                "policy": zip_path,
                "database_outcome": outcome,
                "database_moves": len(lattice) - 1,
                "tight_moves": int(np.sum(slack < TIGHT_CM)),
                "min_slack_cm": float(slack.min()) if len(slack) else None,
                "robot_goal_rate": goals / TRIALS,
                "robot_collisions": len(hits),
                "robot_collision_moves": sorted(set(hits)),
            }
        )
    fig.tight_layout()
    fig.savefig(args.out / "robot_paths.png", dpi=DPI)
    plt.close(fig)
    return {"policies": results}


# --- the database path's readings --------------------------------------------------------------------------------


def database_of(map_name: str, cache: Path) -> tuple[SensorDatabase, Path]:
    """The documented recording of ``map_name`` (8 readings a cell, the stand-in robot, seed 0), cached."""
    path = cache / f"{map_name.replace(':', '_')}_k{K}.npz"
    core = office_core(map_name)
    if not path.exists():
        save_database(record_database(K, map=map_name, model=RealisticModel(), seed=0), path)
    return load_database(path, core), path


def nearest_cells(queries: np.ndarray, means: np.ndarray, chunk: int = 2048) -> np.ndarray:
    """Index of the nearest row of ``means`` to each row of ``queries`` (Euclidean)."""
    sq = (means**2).sum(axis=1)
    out = np.empty(len(queries), dtype=np.int64)
    for i in range(0, len(queries), chunk):
        q = queries[i : i + chunk]
        out[i : i + chunk] = np.argmin(sq[None, :] - 2.0 * q @ means.T, axis=1)
    return out


def readings_stats(core: OfficeCore, db: SensorDatabase) -> dict[str, Any]:
    """Per-cell spread (cm) and aliasing (normalised readings, the policy's input) of a database."""
    cells = np.flatnonzero(db.counts >= 2)
    spread = np.stack([db.cell_readings(int(c)).std(axis=0) for c in cells])  # (cells, 32) cm
    near = np.stack([db.cell_readings(int(c))[:, N_SONAR:].mean(axis=0) for c in cells]) < IR_MAX_CM
    readings = db.readings()
    owner = np.repeat(np.arange(len(db.counts)), db.counts)
    means = np.zeros((len(db.counts), readings.shape[1]))
    np.add.at(means, owner, readings)
    recorded = db.counts > 0
    means[recorded] /= db.counts[recorded, None]
    index = np.flatnonzero(recorded)
    nearest = index[nearest_cells(readings, means[index])]
    # leave-one-out: a reading compared with its own cell's mean without itself
    n = db.counts[owner]
    own = np.where((n > 1)[:, None], (means[owner] * n[:, None] - readings) / np.maximum(n - 1, 1)[:, None], np.inf)
    own_d = np.linalg.norm(readings - own, axis=1)
    other_d = np.linalg.norm(readings - means[nearest], axis=1)
    aliased = (nearest != owner) & (other_d < own_d)
    far = aliased & (np.linalg.norm(db.cells[nearest] - db.cells[owner], axis=1) > FAR_CM)
    within = np.linalg.norm(readings - means[owner], axis=1)
    recording = db.metadata["recording"]
    return {
        "cells": int(recorded.sum()),
        "median_sonar_spread_cm": float(np.median(spread[:, :N_SONAR])),
        "median_ir_spread_cm": float(np.median(spread[:, N_SONAR:])),
        "median_ir_spread_near_cm": float(np.median(spread[:, N_SONAR:][near])),
        "aliased_share": float(aliased.mean()),
        "aliased_far_share": float(far.mean()),
        "median_within_cell_distance": float(np.median(within[n > 1])),
        "median_odometry_error_cm": recording["median_odometry_error_cm"],
        "p95_odometry_error_cm": recording["p95_odometry_error_cm"],
        "bumped_runs": recording["bumped_runs"],
        "bumped_share": recording["bumped_runs"] / (recording["bumped_runs"] + int(db.counts.sum())),
        "means": means,
        "within": within,
        "owner": owner,
    }


def by_step(values: np.ndarray) -> list[float | None]:
    """The median over trials ``(trials, steps)`` of each step that some trial reached (NaN: not reached)."""
    return [float(np.median(v[np.isfinite(v)])) if np.isfinite(v).any() else None for v in values.T]


def robot_drives(core: OfficeCore, map_name: str, db: SensorDatabase, stats: dict[str, Any]) -> dict[str, Any]:
    """:data:`TRIALS` drives of ``NomadOfficeReal-v0`` from the start along two shortest lattice paths
    (:func:`shortest_to_goal`: breadth-first search's and the widest), open loop: their goal rates and collisions; on
    the widest, the drift (true pose - odometry, cm), the gap of each reading to the database readings of the
    odometry's cell (distance to the cell's mean over the cell's median distance of its own readings to it), and
    whether the nearest cell mean lies more than :data:`FAR_CM` away."""
    derived = derived_settings("NomadOffice-v0", {"map": map_name})
    limit = None if derived is None else derived.eval_env_kwargs.get("max_episode_steps")
    env = gym.make("NomadOfficeReal-v0", map=map_name, max_episode_steps=limit)
    cell_median = np.full(len(db.counts), np.nan)
    for c in np.flatnonzero(db.counts > 1):
        cell_median[c] = np.median(stats["within"][stats["owner"] == c])
    recorded = np.flatnonzero(db.counts > 0)
    out: dict[str, Any] = {}
    for name, widest in (("bfs", False), ("widest", True)):
        best = shortest_to_goal(core, into_goal=INTO_GOAL, widest=widest)
        cells = [core.lattice.index(xy) for xy in best]
        actions = [int(np.flatnonzero(core.lattice.moves[a] == b)[0]) for a, b in itertools.pairwise(cells)]
        slack = move_slack(core, np.array(cells[:-1]), np.array(cells[1:]))
        drift = np.full((TRIALS, len(actions)), np.nan)
        gap = np.full((TRIALS, len(actions)), np.nan)
        far = np.zeros((TRIALS, len(actions)), dtype=bool)
        goals, collision_steps = 0, []
        for trial in range(TRIALS):
            obs, _ = env.reset(seed=trial)
            for step, action in enumerate(actions):
                obs, _, terminated, truncated, info = env.step(action)
                if info["collision"]:
                    collision_steps.append(step + 1)
                    break
                cell = cells[step + 1]
                drift[trial, step] = float(np.linalg.norm(np.array(info["position_cm"]) - best[step + 1]))
                if widest:
                    reading = obs[: 2 * N_SONAR]
                    gap[trial, step] = np.linalg.norm(reading - stats["means"][cell]) / cell_median[cell]
                    nearest = recorded[nearest_cells(reading[None], stats["means"][recorded])[0]]
                    far[trial, step] = np.linalg.norm(db.cells[nearest] - db.cells[cell]) > FAR_CM
                if info["is_success"] or terminated or truncated:
                    goals += int(info["is_success"])
                    break
        out |= {
            f"{name}_tight_moves": int(np.sum(slack < TIGHT_CM)),
            f"{name}_min_slack_cm": float(slack.min()),
            f"{name}_goal_rate": goals / TRIALS,
            f"{name}_collisions": len(collision_steps),
            f"{name}_collision_moves": sorted(set(collision_steps)),
        }
        if widest:
            out |= {
                "path_moves": len(actions),
                "final_drift_cm_median": float(
                    np.median([d[np.isfinite(d)][-1] for d in drift if np.isfinite(d).any()])
                ),
                "max_drift_cm": float(np.nanmax(drift)),
                "median_gap_ratio": float(np.nanmedian(gap)),
                "robot_far_share": float(far[np.isfinite(gap)].mean()),
                "drift_by_step": by_step(drift),
                "gap_by_step": by_step(gap),
            }
    env.close()
    return out


def stage_database(args: argparse.Namespace, plt: Any) -> dict[str, Any]:
    offices = []
    for map_name in args.db_maps:
        core = office_core(map_name)
        db, path = database_of(map_name, args.cache)
        stats = readings_stats(core, db)
        drives = robot_drives(core, map_name, db, stats)
        derived = derived_settings("NomadOfficeMemorable-v0", {"map": map_name, "database": str(path)})
        offices.append(
            {"map": map_name, "size": map_name.split(":")[1]}
            | {"shortest_path": (task_facts("NomadOffice-v0", {"map": map_name}) or {}).get("shortest_path")}
            | {k: v for k, v in stats.items() if k not in ("means", "within", "owner")}
            | drives
            | {"derived": None if derived is None else derived.hyperparams | {"check_episodes": derived.check_episodes}}
        )
        print(f"{map_name}: {json.dumps({k: v for k, v in offices[-1].items() if not k.endswith('by_step')})}")
    colours = {"S": "C2", "M": "C0", "L": "C3"}
    fig, grid = plt.subplots(2, 3, figsize=(14, 7.4))
    axes = grid.ravel()
    for office in offices:
        c = colours[office["size"]]
        x = office["shortest_path"]
        axes[0].plot(x, office["median_sonar_spread_cm"], "o", color=c)
        axes[0].plot(x, office["median_ir_spread_near_cm"], "^", color=c)
        axes[1].plot(x, office["aliased_far_share"], "o", color=c)
        axes[1].plot(x, office["robot_far_share"], "s", color=c, mfc="none")
        axes[2].plot(x, office["bumped_share"], "o", color=c)
        axes[3].plot(office["drift_by_step"], "-", color=c, lw=1)
        axes[4].plot(office["gap_by_step"], "-", color=c, lw=1)
        axes[5].plot(x, office["bfs_goal_rate"], "o", color=c)
        axes[5].plot(x, office["widest_goal_rate"], "s", color=c, mfc="none")
    moves = "shortest path (moves)"
    along = "move along the widest shortest path"
    axes[0].set(xlabel=moves, ylabel="median per-cell std (cm)", title="spread: o sonar, ^ IR below its 40 cm maximum")
    axes[1].set(
        xlabel=moves,
        ylabel=f"share nearest cell mean > {FAR_CM:.0f} cm away",
        title="aliasing: o database readings, s the robot's",
    )
    axes[2].set(xlabel=moves, ylabel="share of recording drives", title="recording drives that bumped (re-driven)")
    axes[3].set(xlabel=along, ylabel="median |true - odometry| (cm)", title="the robot's drift (drives not ended yet)")
    axes[4].set(
        xlabel=along,
        ylabel="reading to cell mean / within-cell median",
        title="gap robot - database (1: like a recorded reading)",
        yscale="log",
    )
    axes[5].set(
        xlabel=moves,
        ylabel=f"goal rate ({TRIALS} drives)",
        ylim=(-0.03, 1.03),
        title="the robot on a shortest path: o BFS's, s the widest",
    )
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.title.set_fontsize(9)
    for size, c in colours.items():
        axes[0].plot([], [], "o", color=c, label=size)
    axes[0].legend(fontsize=8)
    fig.suptitle(
        f"Databases recorded as documented ({K} readings a cell, the stand-in robot, seed 0); {TRIALS} drives of "
        "NomadOfficeReal-v0 from the start along a shortest lattice path, open loop",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(args.out / "database_readings.png", dpi=DPI)
    plt.close(fig)
    return {"offices": offices, "far_cm": FAR_CM, "trials": TRIALS, "k": K}


# --- starts, time limit, derived settings ------------------------------------------------------------------------


def office_settings(map_name: str) -> dict[str, Any]:
    """The starts, the time limit and the derived settings (simulator path) of a development office."""
    facts = task_facts("NomadOffice-v0", {"map": map_name}) or {}
    derived = derived_settings("NomadOffice-v0", {"map": map_name})
    robot = gym.make("NomadOffice-v0", map=map_name).unwrapped.robot  # type: ignore[attr-defined]
    starts = robot.goal_distance[robot.start_cells]
    moves = facts["shortest_path"]
    gamma = derived.hyperparams["gamma"] if derived else None
    steps = np.diff(shortest_to_goal(office_core(map_name)), axis=0)
    return {
        "map": map_name,
        "turns": int(np.sum(np.any(steps[1:] != steps[:-1], axis=1))),
        "size": size_class(moves),
        "shortest_path": moves,
        "farthest_start": facts["farthest_start"],
        "start_cells": len(starts),
        "starts_as_far_share": float(np.mean(starts >= moves)),
        "time_limit": facts["time_limit"],
        "gamma": gamma,
        "goal_value_at_start": None if gamma is None else round(gamma**moves, 3),
        "budget": derived.hyperparams["n_timesteps"] if derived else None,
        "ent_coef": derived.hyperparams.get("ent_coef", 0.05) if derived else None,
        "progress": derived.env_kwargs.get("progress", 0.0) if derived else None,
    }


ARMS = (("dev_rows_a", "B"), ("dev_rows_b", "B"), ("dev_rows_2x", "2B"), ("dev_sim_rows", "progress"))
"""The rows files' arms: reliability part A (budget B, no progress), its runs continued to the ceiling 2B, and
every_office A1 (progress 0.05, ceiling 2B)."""


def stage_settings(args: argparse.Namespace, rows: list[dict[str, str]]) -> dict[str, Any]:
    maps = sorted({r["map"] for r in rows} | set(args.db_maps), key=lambda m: (m.split(":")[1], int(m.split(":")[2])))
    outcomes: dict[tuple[str, str], dict[int, str]] = {}
    for row in rows:
        arm = next((label for stem, label in ARMS if Path(row["file"]).stem.startswith(stem)), None)
        if row["algo"] != "twoda2c" or arm is None:
            continue
        steps = f"{int(row['steps']) / 1e6:.2f}M"
        outcomes.setdefault((row["map"], arm), {})[int(row["seed"])] = (
            steps if float(row["goal_rate"]) >= SUCCESS_THRESHOLD else f"failed {steps}"
        )
    offices = []
    for m in maps:
        office = office_settings(m)
        for _, arm in ARMS:
            seeds = outcomes.get((m, arm), {})
            office[f"twoda2c {arm}"] = ", ".join(f"s{s} {seeds[s]}" for s in sorted(seeds)) or None
        offices.append(office)
    return {"offices": offices, "rank_correlations": rank_correlations(offices, rows)}


FACTS = ("shortest_path", "farthest_start", "start_cells", "starts_as_far_share", "turns")


def rank_correlations(offices: list[dict[str, Any]], rows: list[dict[str, str]]) -> dict[str, Any]:
    """Spearman's rank correlation of each task fact with TwoDimA2C's steps to learn without the progress signal
    (mean over seeds of log steps; a run's steps are the first that learned, at B or continued to 2B; a run that
    never learned ranks above every one that did), over the offices with both seeds."""
    from scipy.stats import spearmanr

    never = 1e12
    steps: dict[tuple[str, int], float] = {}
    for row in rows:
        arm = next((label for stem, label in ARMS if Path(row["file"]).stem.startswith(stem)), None)
        if row["algo"] != "twoda2c" or arm not in ("B", "2B"):
            continue
        key = (row["map"], int(row["seed"]))
        learned = float(row["goal_rate"]) >= SUCCESS_THRESHOLD
        steps[key] = min(steps.get(key, never), int(row["steps"]) if learned else never)
    used = [o for o in offices if (o["map"], 1) in steps and (o["map"], 2) in steps]
    y = [np.mean(np.log([steps[(o["map"], 1)], steps[(o["map"], 2)]])) for o in used]
    out: dict[str, Any] = {"offices": len(used)}
    for fact in FACTS:
        result = spearmanr([o[fact] for o in used], y)
        out[fact] = {"rho": round(float(result.statistic), 2), "p": round(float(result.pvalue), 3)}
    return out


# --- summary -----------------------------------------------------------------------------------------------------


def table(rows: list[dict[str, Any]], keys: list[str]) -> str:
    def fmt(v: Any) -> str:
        if isinstance(v, float):
            return f"{v:.3g}"
        if isinstance(v, list):
            return " ".join(map(str, v))
        return "-" if v is None else str(v)

    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(fmt(r.get(k)) for k in keys) + " |" for r in rows]
    return "\n".join(lines)


def write_summary(out: Path) -> None:
    parts = ["# Diagnosis: measured numbers (written by scripts/diagnose_offices.py)\n"]
    stage = {s: json.loads((out / f"{s}.json").read_text()) for s in STAGES if (out / f"{s}.json").exists()}
    if "checks" in stage:
        rows = []
        for r in stage["checks"]["runs"]:
            for arm in ("no progress", "progress 0.05"):
                if arm in r:
                    rows.append({"map": short(r["map"]), "seed": r["seed"], "why": r["why"], "arm": arm} | r[arm])
        parts += [
            "## Goal checks (goal_checks.png)\n",
            table(
                rows,
                [
                    "map",
                    "seed",
                    "why",
                    "arm",
                    "checks",
                    "last_step",
                    "first_pass",
                    "learned_at",
                    "relapses",
                    "time_limit_checks",
                    "collision_checks",
                ],
            ),
            "",
        ]
    if "paths" in stage:
        parts += [
            "## Deterministic paths from the start (paths.png)\n",
            table(
                stage["paths"]["policies"],
                [
                    "label",
                    "map",
                    "outcome",
                    "moves",
                    "time_limit",
                    "loop_start",
                    "loop_period",
                    "stochastic_goal_rate",
                    "stochastic_median_moves",
                    "cells_goal",
                    "cells_collision",
                    "cells_time_limit",
                    "cells_as_far_goal",
                    "top_prob_goal",
                    "top_prob_time_limit",
                    "policy",
                ],
            ),
            "",
        ]
    if stage.get("paths", {}).get("runs"):
        points = [{"label": r["label"], "map": r["map"]} | p for r in stage["paths"]["runs"] for p in r["points"]]
        parts += [
            "## Cells reaching the goal over training (basins.png)\n",
            table(points, ["label", "map", "steps", "cells_goal", "cells_as_far_goal", "from_start"]),
            "",
        ]
    if "robot" in stage:
        parts += [
            "## A database-trained policy on the stand-in robot (robot_paths.png)\n",
            table(
                stage["robot"]["policies"],
                [
                    "label",
                    "map",
                    "database_outcome",
                    "database_moves",
                    "tight_moves",
                    "min_slack_cm",
                    "robot_goal_rate",
                    "robot_collisions",
                    "robot_collision_moves",
                    "policy",
                ],
            ),
            "",
        ]
    if "database" in stage:
        parts += [
            "## Database readings and the stand-in robot (database_readings.png)\n",
            table(
                stage["database"]["offices"],
                [
                    "map",
                    "shortest_path",
                    "cells",
                    "path_moves",
                    "median_sonar_spread_cm",
                    "median_ir_spread_cm",
                    "median_ir_spread_near_cm",
                    "aliased_share",
                    "aliased_far_share",
                    "median_odometry_error_cm",
                    "p95_odometry_error_cm",
                    "bumped_share",
                    "median_gap_ratio",
                    "robot_far_share",
                    "final_drift_cm_median",
                    "max_drift_cm",
                    "bfs_tight_moves",
                    "bfs_min_slack_cm",
                    "bfs_goal_rate",
                    "bfs_collisions",
                    "bfs_collision_moves",
                    "widest_tight_moves",
                    "widest_min_slack_cm",
                    "widest_goal_rate",
                    "widest_collisions",
                    "widest_collision_moves",
                    "derived",
                ],
            ),
            "",
        ]
    if "settings" in stage:
        parts += [
            "## Starts, time limit, derived settings (simulator path)\n",
            "The settings the recipe derives now (revision 2: the progress signal on every size); the runs of "
            "`results/reliability` (columns B and 2B) had revision 1's, the same without the signal on M and S. "
            "`starts_as_far_share`: the share of the training start cells (uniform over the reachable cells) at least "
            "as far from the goal as the map's start; `goal_value_at_start`: gamma to the power of the shortest "
            "path; `turns`: turns of breadth-first search's shortest path.\n",
            table(
                stage["settings"]["offices"],
                [
                    "map",
                    "size",
                    "shortest_path",
                    "farthest_start",
                    "start_cells",
                    "starts_as_far_share",
                    "time_limit",
                    "gamma",
                    "goal_value_at_start",
                    "budget",
                    "ent_coef",
                    "progress",
                    "turns",
                    "twoda2c B",
                    "twoda2c 2B",
                    "twoda2c progress",
                ],
            ),
            "",
        ]
        correlations = stage["settings"]["rank_correlations"]
        parts += [
            f"Spearman rank correlation with the steps to learn without progress (TwoDimA2C, "
            f"{correlations['offices']} offices, both seeds):\n",
            table([{"fact": f} | correlations[f] for f in FACTS], ["fact", "rho", "p"]),
            "",
        ]
    (out / "summary.md").write_text("\n".join(parts))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True, help="folder for the figures, JSON and summary.md")
    parser.add_argument("--stages", nargs="+", choices=STAGES, default=list(STAGES))
    reliability, every = Path("results/reliability"), Path("results/every_office")
    parser.add_argument("--before", type=Path, nargs="+", default=sorted(reliability.glob("dev_checks_*.jsonl")))
    parser.add_argument("--before-rows", type=Path, nargs="+", default=sorted(reliability.glob("dev_rows_*.csv")))
    parser.add_argument("--after", type=Path, nargs="+", default=[every / "dev_sim_checks.jsonl"])
    parser.add_argument("--after-rows", type=Path, nargs="+", default=[every / "dev_sim_rows.csv"])
    parser.add_argument(
        "--after-run",
        nargs=2,
        action="append",
        default=[],
        metavar=("MAP:SEED", "FOLDER"),
        help="a train command's run folder with progress 0.05 (its goal_checks.json), where the study has no row yet",
    )
    parser.add_argument(
        "--policy",
        nargs=4,
        action="append",
        default=[],
        metavar=("LABEL", "ALGO", "MAP", "ZIP"),
        help="a saved policy whose deterministic path from the map's start is drawn",
    )
    parser.add_argument(
        "--run",
        nargs=4,
        action="append",
        default=[],
        metavar=("LABEL", "ALGO", "MAP", "FOLDER"),
        help="a run folder with --save-freq checkpoints: the cells reaching the goal over training",
    )
    parser.add_argument(
        "--robot-policy",
        nargs=5,
        action="append",
        default=[],
        metavar=("LABEL", "ALGO", "MAP", "DATABASE", "ZIP"),
        help="a policy trained on a database: its path there and its trials on the stand-in robot",
    )
    parser.add_argument("--db-maps", type=dev_map, nargs="*", default=[])
    parser.add_argument("--cache", type=Path, default=Path("/tmp/diagnose_offices"), help="recorded databases")
    args = parser.parse_args(argv)
    for flag, entries in (("--policy", args.policy), ("--run", args.run), ("--robot-policy", args.robot_policy)):
        for entry in entries:
            try:
                dev_map(entry[2])
            except argparse.ArgumentTypeError as err:
                parser.error(f"{flag}: {err}")
    args.out.mkdir(parents=True, exist_ok=True)
    args.cache.mkdir(parents=True, exist_ok=True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for name in args.stages:
        if (name == "paths" and not args.policy) or (name == "robot" and not args.robot_policy):
            continue
        if name == "database" and not args.db_maps:
            continue
        if name == "checks":
            result = stage_checks(args, plt)
        elif name == "paths":
            result = stage_paths(args, plt)
        elif name == "robot":
            result = stage_robot(args, plt)
        elif name == "database":
            result = stage_database(args, plt)
        else:
            result = stage_settings(args, read_rows(args.before_rows + args.after_rows))
        (args.out / f"{name}.json").write_text(json.dumps(result, indent=1) + "\n")
        print(f"wrote {args.out / name}.json")
    write_summary(args.out)
    print(f"wrote {args.out / 'summary.md'}")


if __name__ == "__main__":
    main()
