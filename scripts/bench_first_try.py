"""Does a user's office learn on the first try? ``sb3-twodrl-train`` run as docs/own_office.md writes it, per map.

For each map and algorithm it runs, in a fresh process and an empty folder,

    sb3-twodrl-train --algo ALGO --env NomadOffice-v0 --env-kwargs map:'"MAP"'

with no ``--seed`` (rl-zoo3 then draws one, as for any user; the row records it), and reads the command's own
output: the goal rate of its 20 deterministic test episodes from the map's start, and its ``goal_checks.json``
(the kept check, whether it stopped as learned, training seconds). Rows are appended to ``--out`` (a map and
algorithm already there are skipped: the run resumes); ``--table`` prints the table of rows files.

``--database`` runs, per generated map, docs/own_office.md's database path as the doc writes it, from its own
text: ``sb3-twodrl-map --seed SEED --size SIZE --out my_office.json``, then the doc's record, train
(``NomadOfficeMemorable-v0``) and export commands and its robot-side loop (20 trials on the stand-in robot from the
map's start); the row's ``goal_rate`` is the loop's, ``db_goal_rate`` the train command's.

``--robot-path`` runs, per generated map, docs/robot_path.md as the doc writes it, the map file in the place of the
paper's office: survey the MuJoCo robot into a bag, import it by the localised pose, train, export by the printed
line, drive the MuJoCo robot 20 trials from the start (``goal_rate``); then the same policy on the other stand-in,
the artifact model (``real_goal_rate``), and the simulator path's policy (the documented simulator command on the
same map, exported by its printed line) on the MuJoCo robot (``sim_goal_rate``). Each part's seconds are recorded.

    OMP_NUM_THREADS=1 python scripts/bench_first_try.py --algos twoda2c --sizes S M --map-seeds 5000 5001 \\
        --out results/first_try/rows_twoda2c.csv
    python scripts/bench_first_try.py --table results/first_try/rows_*.csv --plot results/first_try/fig_time.png
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
import re
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

import twodrl_envs  # noqa: F401  (registers NomadOffice-v0, for its task facts)
from sb3_twodrl.callbacks import SUCCESS_THRESHOLD
from twodrl_bench.folders import append_row
from twodrl_bench.intervals import wilson
from twodrl_zoo.hyperparams import task_facts
from twodrl_zoo.recipe import derive, size_class

FIELDS = (
    "map", "size", "moves", "algo", "seed", "goal_rate", "learned", "stopped_learned", "kept_at", "steps", "budget",
    "train_s", "wall_s", "commit", "cpu",
)  # fmt: skip
DATABASE_FIELDS = (*FIELDS, "db_goal_rate")
ROBOT_FIELDS = (*DATABASE_FIELDS, "survey_s", "import_s", "real_goal_rate", "sim_goal_rate")
LINE = re.compile(r"goal rate (\d\.\d\d) \((\d+) of (\d+)")
EXPORT = re.compile(r"^sb3-twodrl-train: export: (.*)$", re.MULTILINE)
STAND_IN = re.compile(r"^goal rate on the stand-in robot: (\d\.\d\d)", re.MULTILINE)
AGREE = 0.2
"""On the database path, the final test and the robot agree when their goal rates differ by at most this."""
MUJOCO = re.compile(r"^goal rate on the MuJoCo robot: (\d\.\d\d)", re.MULTILINE)
DOC = Path(__file__).resolve().parents[1] / "docs" / "own_office.md"
ROBOT_DOC = DOC.parent / "robot_path.md"
MAP_FILE = "my_office.json"


def _row(map_: str, size: str, moves: int, algo: str, seed: int, rate: float, record: dict) -> dict[str, object]:
    """A row's columns from the command's goal rate and its ``goal_checks.json`` record."""
    return {
        "map": map_,
        "size": size,
        "moves": moves,
        "algo": algo,
        "seed": seed,
        "goal_rate": rate,
        "learned": rate >= SUCCESS_THRESHOLD,
        "stopped_learned": record["learned_at"] is not None,
        "kept_at": record["kept"]["timesteps"] if record["kept"] else "",
        "steps": record["num_timesteps"],
        "budget": record["n_timesteps"],
        "train_s": record["train_s"],
    }


def _with(command: str, extra: list[str]) -> str:
    """The train ``command`` with ``extra``: ``key:value`` items join its ``--env-kwargs`` (a new one if none),
    ``--flag value`` items go at its end (``--hyperparams key:value`` too: an item right after a flag is its
    value)."""
    options, flags = [], []
    for i, a in enumerate(extra):
        is_option = not a.startswith("-") and ":" in a and not (i > 0 and extra[i - 1].startswith("--"))
        (options if is_option else flags).append(a)
    if options:
        kwargs = " ".join(options)
        command = (
            command.replace("--env-kwargs ", f"--env-kwargs {kwargs} ")
            if "--env-kwargs " in command
            else (f"{command} --env-kwargs {kwargs}")
        )
    return " ".join([command, *flags])


def doc_database_path() -> tuple[list[str], str]:
    """docs/own_office.md's database commands (record with --out, train on the database, export) and its
    robot-side loop, as written."""
    text = DOC.read_text()
    steps = text[text.index("## 3. ") : text.index("## Start from a generated office")]
    lines = [line[2:] for line in steps.splitlines() if line.startswith("$ sb3-twodrl-")]
    commands = [c for c in lines if "--out" in c or "NomadOfficeMemorable-v0" in c]
    loop = text[text.index("## 5. ") :].split("```python\n", 1)[1].split("```", 1)[0]
    return commands, loop


def _shell(folder: str, command: str) -> tuple[str, float]:
    """``command`` run by bash in ``folder``: its stdout and seconds; a failure raises, naming the command."""
    clock = time.perf_counter()
    done = subprocess.run(["bash", "-c", command], cwd=folder, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{command} failed:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
    return done.stdout, time.perf_counter() - clock


def _run_doc(folder: str, commands: list[str]) -> tuple[str, dict[str, float]]:
    """A doc's ``commands`` run in order in ``folder``, its export line replaced by the one the train command printed
    (the doc says to run that line): their stdout, and each program's seconds."""
    out, seconds = "", {}
    for command in commands:
        printed = EXPORT.findall(out)
        if command.startswith("sb3-twodrl-export") and printed:
            command = printed[-1]
        stdout, seconds[command.split()[0]] = _shell(folder, command)
        out += stdout
    return out, seconds


def _drive(folder: str, loop: str, result: re.Pattern[str]) -> float:
    """A doc's robot loop run in ``folder``: the goal rate it printed (``result``)."""
    done = subprocess.run([sys.executable, "-c", loop], cwd=folder, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"the robot loop failed:\n{done.stderr[-2000:]}")
    return float(result.search(done.stdout).group(1))  # type: ignore[union-attr]


def run_database(
    map_: str, commit: str, cpu: str, algo: str = "twoda2c", extra: list[str] = (), checks: Path | None = None
) -> dict[str, object]:
    """docs/own_office.md's database path on the generated office ``map_`` (``generated:SIZE:SEED``), its train
    command with ``--algo algo`` and ``extra`` arguments; the run's ``goal_checks.json`` appended to ``checks``."""
    _, size, map_seed = map_.split(":")
    commands, loop = doc_database_path()
    commands = [
        _with(c.replace("twoda2c", algo), extra) if "-train " in c else c.replace("twoda2c", algo) for c in commands
    ]
    with tempfile.TemporaryDirectory() as folder:
        clock = time.perf_counter()
        out, _ = _run_doc(folder, [f"sb3-twodrl-map --seed {map_seed} --size {size} --out my_office.json", *commands])
        rate = _drive(folder, loop, STAND_IN)
        wall = time.perf_counter() - clock
        (record_file,) = Path(folder).glob("logs/*/*/goal_checks.json")
        record = json.loads(record_file.read_text())
    facts = task_facts("NomadOffice-v0", {"map": map_})
    assert facts is not None
    seed = int(re.search(r"^Seed: (\d+)$", out, re.MULTILINE).group(1))  # type: ignore[union-attr]
    if checks is not None:
        with checks.open("a") as f:
            f.write(json.dumps({"map": map_, "algo": f"{algo}-database", "seed": seed, **record}, default=str) + "\n")
    return {
        **_row(
            map_, size_class(facts["shortest_path"]), facts["shortest_path"], f"{algo}-database", seed, rate, record
        ),
        "wall_s": round(wall, 1),
        "commit": commit,
        "cpu": cpu,
        "db_goal_rate": float(LINE.search(out).group(1)),  # type: ignore[union-attr]
    }


def doc_robot_path(map_file: str = MAP_FILE) -> tuple[list[str], str]:
    """docs/robot_path.md's survey, import (by the localised pose), train and export commands and its drive on the
    MuJoCo robot, with the map file ``map_file`` where the doc names the paper's office."""
    text = ROBOT_DOC.read_text()

    def on_map(line: str) -> str:
        return (
            line.replace("--map office", f"--map {map_file}")
            .replace("""map:'"office"'""", f"""map:'"{map_file}"'""")
            .replace('map="office"', f'map="{map_file}"')
        )

    lines = [line[2:] for line in text.splitlines() if line.startswith("$ sb3-twodrl-")]
    commands = [on_map(c) for c in lines if "office_odom.npz" not in c and not c.startswith("sb3-twodrl-replay-bag")]
    return commands, on_map(text[text.index("## 5. ") :].split("```python\n", 1)[1].split("```", 1)[0])


def run_robot_path(
    map_: str, commit: str, cpu: str, algo: str = "twoda2c", extra: list[str] = (), checks: Path | None = None
) -> dict[str, object]:
    """docs/robot_path.md on the generated office ``map_`` (module docstring; ``"office"``: the doc as written, on
    the paper's office), its train command with ``--algo algo`` and ``extra`` arguments; the run's
    ``goal_checks.json`` appended to ``checks``."""
    paper = map_ == "office"
    commands, loop = doc_robot_path(MAP_FILE if not paper else "office")
    commands = [_with(c.replace("twoda2c", algo), extra) if "-train " in c else c for c in commands]
    with tempfile.TemporaryDirectory() as folder:
        clock = time.perf_counter()
        if not paper:
            _, size, map_seed = map_.split(":")
            commands = [f"sb3-twodrl-map --seed {map_seed} --size {size} --out {MAP_FILE}", *commands]
        out, seconds = _run_doc(folder, commands)
        rate = _drive(folder, loop, MUJOCO)
        wall = time.perf_counter() - clock
        (record_file,) = Path(folder).glob("logs/*/*/goal_checks.json")
        record = json.loads(record_file.read_text())
        real = _drive(folder, loop.replace("NomadOfficeMuJoCo-v0", "NomadOfficeReal-v0"), MUJOCO)
        on_map = "" if paper else f""" --env-kwargs map:'"{MAP_FILE}"'"""
        simulator, _ = _shell(folder, f"sb3-twodrl-train --algo {algo} --env NomadOffice-v0{on_map}")
        _shell(folder, EXPORT.findall(simulator)[-1].replace(" policy.onnx ", " simulator.onnx "))
        sim = _drive(folder, loop.replace('"policy.onnx"', '"simulator.onnx"'), MUJOCO)
    facts = task_facts("NomadOffice-v0", {} if paper else {"map": map_})
    seed = int(re.search(r"^Seed: (\d+)$", out, re.MULTILINE).group(1))  # type: ignore[union-attr]
    if checks is not None:
        with checks.open("a") as f:
            f.write(json.dumps({"map": map_, "algo": f"{algo}-robot", "seed": seed, **record}, default=str) + "\n")
    moves = 17 if facts is None else facts["shortest_path"]
    return {
        **_row(map_, "paper" if facts is None else size_class(moves), moves, f"{algo}-robot", seed, rate, record),
        "wall_s": round(wall, 1),
        "commit": commit,
        "cpu": cpu,
        "db_goal_rate": float(LINE.search(out).group(1)),  # type: ignore[union-attr]
        "survey_s": round(seconds["sb3-twodrl-survey"], 1),
        "import_s": round(seconds["sb3-twodrl-record-database"], 1),
        "real_goal_rate": real,
        "sim_goal_rate": sim,
    }


def run(
    algo: str,
    map_: str,
    commit: str,
    cpu: str,
    seed: int | None = None,
    checks: Path | None = None,
    budget_factor: float | None = None,
    extra: list[str] = (),
) -> dict[str, object]:
    """One run of the command on ``map_`` (``"office"``: the paper's office, no ``--env-kwargs``), with ``--seed
    seed`` where given and ``-n`` ``budget_factor`` times the derived budget where given; its ``goal_checks.json``
    record appended to ``checks`` (JSON lines) where given."""
    facts = task_facts("NomadOffice-v0", {} if map_ == "office" else {"map": map_})
    command = ["sb3-twodrl-train", "--algo", algo, "--env", "NomadOffice-v0"]
    if map_ != "office":
        command += ["--env-kwargs", f'map:"{map_}"']
    if seed is not None:
        command += ["--seed", str(seed)]
    if budget_factor is not None:
        assert facts is not None, f"{map_} derives no budget"
        command += ["-n", str(int(budget_factor * derive(facts).hyperparams["n_timesteps"]))]
    command = _with(" ".join(command), extra).split(" ")
    with tempfile.TemporaryDirectory() as folder:
        clock = time.perf_counter()
        done = subprocess.run(command, cwd=folder, capture_output=True, text=True)
        wall = time.perf_counter() - clock
        records = list(Path(folder).glob("logs/*/*/goal_checks.json"))
        if done.returncode != 0 or len(records) != 1:
            raise RuntimeError(f"{' '.join(command)} failed:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
        record = json.loads(records[0].read_text())
    seed = int(re.search(r"^Seed: (\d+)$", done.stdout, re.MULTILINE).group(1))  # type: ignore[union-attr]
    rate = float(LINE.search(done.stdout).group(1))  # type: ignore[union-attr]
    if checks is not None:
        with checks.open("a") as f:
            f.write(json.dumps({"map": map_, "algo": algo, "seed": seed, **record}, default=str) + "\n")
    moves = 17 if facts is None else facts["shortest_path"]
    size = "paper" if facts is None else size_class(moves)
    return {**_row(map_, size, moves, algo, seed, rate, record), "wall_s": round(wall, 1), "commit": commit, "cpu": cpu}


def table(rows: list[dict[str, str]]) -> str:
    """Per size and algorithm: offices at goal rate >= 0.8 (95% Wilson interval), wall seconds median and max; where
    every row is of the database path (``db_goal_rate``), also the runs whose final test and robot agree
    (:data:`AGREE`); where every row is of the robot path, also the offices the same policy drives to the goal on
    the artifact model and those the simulator's policy drives there on the MuJoCo robot, and each part's seconds."""
    database = all(r.get("db_goal_rate") for r in rows)
    robot = all(r.get("real_goal_rate") for r in rows)
    extra = (" final test and robot within 0.2 |" if database else "") + (
        f" on the artifact model >= {SUCCESS_THRESHOLD} | simulator policy on MuJoCo >= {SUCCESS_THRESHOLD} "
        "| survey s | import s | training s |"
        if robot
        else ""
    )
    lines = [
        f"| size | algo | offices at goal rate >= {SUCCESS_THRESHOLD} [95% interval] | share | stopped as learned "
        f"| wall s, median (max) |{extra}",
        "| --- | --- | --- | --- | --- | --- |" + " --- |" * extra.count("|"),
    ]

    def median_max(group: list[dict[str, str]], field: str) -> str:
        values = sorted(float(r[field]) for r in group)
        return f"{np.median(values):.0f} ({values[-1]:.0f})"

    def count(group: list[dict[str, str]], field: str) -> str:
        good = sum(float(r[field]) >= SUCCESS_THRESHOLD for r in group)
        low, high = wilson(good, len(group))
        return f"{good}/{len(group)} [{low:.2f}, {high:.2f}]"

    for size in ("paper", "S", "M", "S+M", "L"):
        for algo in sorted({r["algo"] for r in rows}, reverse=True):
            group = [
                r for r in rows if r["algo"] == algo and (r["size"] == size or (size == "S+M" and r["size"] in "SM"))
            ]
            if not group:
                continue
            good = sum(r["learned"] == "True" for r in group)
            stopped = sum(r["stopped_learned"] == "True" for r in group)
            cells = [
                count(group, "goal_rate"),
                f"{good / len(group):.2f}",
                f"{stopped}/{len(group)}",
                median_max(group, "wall_s"),
            ]
            if database:
                close = sum(abs(float(r["goal_rate"]) - float(r["db_goal_rate"])) <= AGREE + 1e-9 for r in group)
                cells.append(f"{close}/{len(group)}")
            if robot:
                cells += [count(group, "real_goal_rate"), count(group, "sim_goal_rate")]
                cells += [median_max(group, f) for f in ("survey_s", "import_s", "train_s")]
            lines.append(f"| {size} | {algo} | " + " | ".join(cells) + " |")
    commits = Counter(r["commit"] for r in rows)
    if len(commits) > 1:
        lines += ["", "Rows by the commit that ran them: " + ", ".join(f"`{c}` {n}" for c, n in commits.items()) + "."]
    head = "| map | moves | algo | seed | goal rate | kept at | steps | budget | wall s |"
    more = (" final test |" if database else "") + (" artifact model | simulator policy |" if robot else "")
    lines += ["", head + more, "|" + " --- |" * (9 + more.count("|"))]
    for r in sorted(rows, key=lambda r: (int(r["moves"]), r["map"], r["algo"])):
        lines.append(
            f"| {r['map']} | {r['moves']} | {r['algo']} | {r['seed']} | {float(r['goal_rate']):.2f} | {r['kept_at']} | "
            f"{r['steps']} | {r['budget']} | {r['wall_s']} |"
            + (f" {float(r['db_goal_rate']):.2f} |" if database else "")
            + (f" {float(r['real_goal_rate']):.2f} | {float(r['sim_goal_rate']):.2f} |" if robot else "")
        )
    return "\n".join(lines) + "\n"


def _learned_by(record: dict, steps: float) -> bool:
    """Whether a check of the run ``record`` (``goal_checks.json``) up to ``steps`` reached 0.8."""
    return any(c["goal_rate"] >= SUCCESS_THRESHOLD for c in record["checks"] if c["timesteps"] <= steps)


def restart_table(
    records: list[dict], longer: list[dict] = (), fractions: tuple[float, ...] = (0.2, 0.3, 0.4, 0.5)
) -> str:
    """The offline analysis of ``results/reliability/preregistration.md``: per map, each seed's run as the first
    attempt and the other's as the restart, when no check reached the goal by ``f`` of the budget ``B``; the
    restart within ``B`` or with a whole ``B`` of its own; and the ceiling ``2B`` from ``longer`` (the runs that
    did not learn, continued to ``2B``, whose checks up to ``B`` must be the recorded ones). Learned pairs and mean
    steps spent, against no change.

    :raises ValueError: if a continued run's checks up to ``B`` differ from the recorded run's
    """
    runs: dict[str, list[dict]] = {}
    for record in records:
        runs.setdefault(record["map"], []).append(record)
    continued = {(r["map"], r["seed"]): r for r in longer}
    for record in records:
        more = continued.get((record["map"], record["seed"]))
        if more is not None and more["checks"][: len(record["checks"])] != record["checks"]:
            raise ValueError(f"{record['map']} seed {record['seed']}: the run to 2B is not the recorded one continued")
    pairs = [(a, b) for group in runs.values() if len(group) == 2 for a, b in (group, group[::-1])]

    def outcome(first: dict, second: dict, fraction: float | None, own_budget: bool) -> tuple[bool, int]:
        budget = first["n_timesteps"]
        late = [c["timesteps"] for c in first["checks"] if fraction is not None and c["timesteps"] >= fraction * budget]
        if not late or max(c["goal_rate"] for c in first["checks"] if c["timesteps"] <= late[0]) > 0.0:
            return _learned_by(first, budget), first["num_timesteps"]
        left = budget if own_budget else budget - late[0]
        return _learned_by(second, left), late[0] + min(second["num_timesteps"], left)

    def ceiling(first: dict) -> tuple[bool, int]:
        budget = first["n_timesteps"]
        if _learned_by(first, budget):
            return True, first["num_timesteps"]
        more = continued.get((first["map"], first["seed"]))
        if more is None:
            raise ValueError(f"{first['map']} seed {first['seed']} did not learn and has no run to 2B")
        return _learned_by(more, 2 * budget), more["num_timesteps"]

    candidates: list[tuple[str, Any]] = [("no change (ceiling B)", lambda a, b: outcome(a, b, None, False))]
    for f in fractions:
        candidates.append((f"restart at {f:.1f} B within B", lambda a, b, f=f: outcome(a, b, f, False)))
        candidates.append((f"restart at {f:.1f} B, a whole B after it", lambda a, b, f=f: outcome(a, b, f, True)))
    if longer:
        candidates.append(("ceiling 2B", lambda a, b: ceiling(a)))
    lines = ["| candidate | learned pairs | mean steps |", "| --- | --- | --- |"]
    for name, result in candidates:
        outcomes = [result(a, b) for a, b in pairs]
        steps = sum(s for _, s in outcomes) / max(len(pairs), 1)
        lines.append(f"| {name} | {sum(ok for ok, _ in outcomes)}/{len(pairs)} | {steps:,.0f} |")
    return "\n".join(lines) + "\n"


def compare_table(new: list[dict[str, str]], old: list[dict[str, str]], longer: list[dict[str, str]] = ()) -> str:
    """The runs of ``new`` beside those of ``old`` with the same map, algorithm and seed (the ``old`` runs that did
    not learn continued to twice the budget in ``longer``): per algorithm, runs at goal rate >= 0.8 (``old``
    within its budget and within twice it) and the median steps of the runs that learned; then every pair. Only
    maps whose every ``new`` run of an algorithm finished both seeds count (as many seeds as ``old`` has)."""
    continued = {(r["map"], r["algo"], r["seed"]): r for r in longer}
    before = {(r["map"], r["algo"], r["seed"]): r for r in old}

    def learned(r: dict[str, str]) -> bool:
        return float(r["goal_rate"]) >= SUCCESS_THRESHOLD

    def within_2b(r: dict[str, str]) -> tuple[bool, int]:
        more = continued.get((r["map"], r["algo"], r["seed"]))
        if learned(r) or more is None:
            return learned(r), int(r["steps"])
        return learned(more), int(more["steps"])

    seeds = {
        (r["map"], r["algo"]): {x["seed"] for x in old if (x["map"], x["algo"]) == (r["map"], r["algo"])} for r in new
    }
    pairs = [
        (r, before[(r["map"], r["algo"], r["seed"])])
        for r in new
        if (r["map"], r["algo"], r["seed"]) in before
        and seeds[(r["map"], r["algo"])] <= {x["seed"] for x in new if (x["map"], x["algo"]) == (r["map"], r["algo"])}
    ]
    lines = [
        "| algo | runs | new: learned | new: median steps, learned | old: learned in B | old: learned in 2B "
        "| old: median steps, learned in 2B |",
        "|" + " --- |" * 7,
    ]
    for algo in sorted({r["algo"] for r, _ in pairs}, reverse=True):
        group = [(r, o) for r, o in pairs if r["algo"] == algo]
        steps_new = [int(r["steps"]) for r, _ in group if learned(r)]
        old_2b = [within_2b(o) for _, o in group]
        lines.append(
            f"| {algo} | {len(group)} | {len(steps_new)}/{len(group)} | {np.median(steps_new):,.0f} | "
            f"{sum(learned(o) for _, o in group)}/{len(group)} | {sum(ok for ok, _ in old_2b)}/{len(group)} | "
            f"{np.median([s for ok, s in old_2b if ok]):,.0f} |"
        )
    lines += ["", "| map | algo | seed | new goal rate | new steps | old goal rate | old steps | old in 2B: steps |"]
    lines.append("|" + " --- |" * 8)
    for r, o in pairs:
        ok, steps = within_2b(o)
        lines.append(
            f"| {r['map']} | {r['algo']} | {r['seed']} | {float(r['goal_rate']):.2f} | {int(r['steps']):,} | "
            f"{float(o['goal_rate']):.2f} | {int(o['steps']):,} | {f'{steps:,}' if ok else 'not learned'} |"
        )
    return "\n".join(lines) + "\n"


def plot(rows: list[dict[str, str]], path: Path) -> None:
    """Wall seconds of the whole command against the office's shortest path, per arm; offices below 0.8 hollow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(7, 4))
    styles = (("twoda2c", "o", "C0"), ("a2c", "s", "C1"), ("twoda2c-database", "^", "C2"))
    for algo, marker, color in styles:
        group = [r for r in rows if r["algo"] == algo]
        for good in (True, False):
            chosen = [r for r in group if (r["learned"] == "True") == good]
            if chosen:
                axes.scatter(
                    [int(r["moves"]) for r in chosen],
                    [float(r["wall_s"]) for r in chosen],
                    marker=marker,
                    facecolors=color if good else "none",
                    edgecolors=color,
                    label=f"{algo}" + ("" if good else f", goal rate < {SUCCESS_THRESHOLD}"),
                )
    axes.set_xlabel("shortest path (moves)")
    axes.set_ylabel("wall seconds of the command")
    axes.set_yscale("log")
    axes.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="*", default=[], help="maps as the env takes them ('office': the paper's)")
    parser.add_argument("--sizes", nargs="*", default=[], help="size classes of generated maps (S, M, L)")
    parser.add_argument("--map-seeds", nargs="*", type=int, default=[], help="generated map seeds")
    parser.add_argument("--algos", nargs="+", default=["twoda2c"])
    parser.add_argument("--seeds", nargs="*", type=int, default=[], help="training seeds (default: none, drawn)")
    parser.add_argument(
        "--repeats", type=int, default=1, help="runs per map and arm with drawn seeds (rows already in --out count)"
    )
    parser.add_argument("--budget-factor", type=float, help="-n this times the derived budget (default: not given)")
    parser.add_argument("--checks", type=Path, help="JSON lines file to append each run's goal_checks.json to")
    path = parser.add_mutually_exclusive_group()
    path.add_argument("--database", action="store_true", help="docs/own_office.md's database path")
    path.add_argument("--robot-path", action="store_true", help="docs/robot_path.md on the MuJoCo robot")
    parser.add_argument(
        "--train-args",
        default="",
        help="more arguments of the train command, one string: key:value env options "
        "join its --env-kwargs, e.g. 'progress:0.05 --eval-episodes 20'",
    )
    parser.add_argument("--out", type=Path, help="CSV to append rows to")
    parser.add_argument("--table", type=Path, nargs="+", help="print the table of rows CSVs and exit")
    parser.add_argument("--plot", type=Path, help="with --table: also draw wall seconds against shortest path here")
    parser.add_argument("--restarts", type=Path, nargs="+", help="print the restart analysis of --checks files")
    parser.add_argument("--compare", type=Path, nargs="+", help="print these rows beside --against's, run by run")
    parser.add_argument("--against", type=Path, nargs="*", default=[], help="with --compare: the rows to compare with")
    parser.add_argument("--longer", type=Path, nargs="*", default=[], help="with --restarts: the runs to 2B")
    args = parser.parse_args()
    if args.compare is not None:

        def read(paths: list[Path]) -> list[dict[str, str]]:
            return [row for path in paths for row in csv.DictReader(path.open(newline=""))]

        longer = [p for p in args.longer]
        print(compare_table(read(args.compare), read(args.against), read(longer)), end="")
        return
    if args.restarts is not None:
        records = [json.loads(line) for path in args.restarts for line in path.read_text().splitlines()]
        longer = [json.loads(line) for path in args.longer for line in path.read_text().splitlines()]
        print(restart_table(records, longer), end="")
        return
    if args.table is not None:
        rows = []
        for path in args.table:
            with path.open(newline="") as f:
                rows += list(csv.DictReader(f))
        print(table(rows), end="")
        if args.plot is not None:
            plot(rows, args.plot)
        return
    maps = list(args.maps) + [f"generated:{s}:{seed}" for seed in args.map_seeds for s in args.sizes]
    if args.repeats < 1 or (args.repeats > 1 and args.seeds):
        parser.error(f"--repeats {args.repeats}: a positive count, with drawn seeds only (no --seeds)")
    done: Counter[tuple[str, str, str | None]] = Counter()
    if args.out.exists():
        with args.out.open(newline="") as f:
            done.update((r["map"], r["algo"], r["seed"] if args.seeds else None) for r in csv.DictReader(f))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if "model name" in line), "")
    cpu = cpu or platform.processor()
    fields = ROBOT_FIELDS if args.robot_path else DATABASE_FIELDS if args.database else FIELDS
    for map_ in maps:
        for algo in args.algos:
            for seed in args.seeds or [None] * args.repeats:
                label = f"{algo}-robot" if args.robot_path else f"{algo}-database" if args.database else algo
                key = (map_, label, None if seed is None else str(seed))
                if done[key] > 0:
                    done[key] -= 1
                    continue
                if args.robot_path:
                    row = run_robot_path(map_, commit, cpu, algo, args.train_args.split(), args.checks)
                elif args.database:
                    row = run_database(map_, commit, cpu, algo, args.train_args.split(), args.checks)
                else:
                    row = run(algo, map_, commit, cpu, seed, args.checks, args.budget_factor, args.train_args.split())
                print(" | ".join(str(row[f]) for f in fields), flush=True)
                append_row(args.out, fields, row)


if __name__ == "__main__":
    sys.exit(main())
