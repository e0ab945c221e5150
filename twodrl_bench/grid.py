"""The grid of (algo, seed) runs: backends (serial, worker processes, Ray tasks), tidy CSV, resume.

Each finished run's rows go to ``pairs/<algo>_seed<seed>.csv`` (written atomically: a file there
is complete); a run with such a file is done, a run without one resumes from its checkpoint (see
:mod:`.runner`) in whichever backend runs it. ``results.csv`` collects all pair files.
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import io
import json
import multiprocessing as mp
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from twodrl_bench.checkpoint import atomic_write_bytes
from twodrl_bench.epochs import Row, checkpoint_path, progress_path, run_pair
from twodrl_bench.protocol import COLUMNS, RunSpec

BACKENDS = ("process", "ray", "serial")


def pair_csv(out_dir: str | Path, name: str) -> Path:
    return Path(out_dir) / "pairs" / f"{name}.csv"


def write_rows(path: Path, rows: list[Row]) -> None:
    """Write rows as CSV atomically (temporary file, then rename)."""
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=COLUMNS)
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_bytes(path, buf.getvalue().encode())


def collect_results(out_dir: str | Path):
    """All pair files of ``out_dir`` as one tidy DataFrame (one row per algo, seed, epoch)."""
    import pandas as pd

    files = sorted((Path(out_dir) / "pairs").glob("*.csv"))
    if not files:
        return pd.DataFrame(columns=COLUMNS)
    df = pd.concat([pd.read_csv(f) for f in files], ignore_index=True)
    return df.sort_values(["algo", "seed", "epoch"]).reset_index(drop=True)[COLUMNS]


def check_config(out_dir: str | Path, config: dict[str, Any]) -> None:
    """Refuse to resume ``out_dir`` under another protocol; algos and seeds may be added.

    ``config`` has ``env_id``, ``epochs``, ``learn_episodes``, ``test_episodes``, ``vec_env``,
    ``env_kwargs`` and ``hyperparams`` (per algo); the algos of an earlier invocation stay in the stored config.
    """
    path = Path(out_dir) / "config.json"
    if path.exists():
        old = json.loads(path.read_text())
        old_hp = old.get("hyperparams", {})
        keys = ("env_id", "epochs", "learn_episodes", "test_episodes", "vec_env", "env_kwargs")
        diff = [k for k in keys if old.get(k, {} if k == "env_kwargs" else None) != config.get(k)]
        diff += [
            f"hyperparams of {a}"
            for a in sorted(old_hp.keys() & config["hyperparams"].keys())
            if old_hp[a] != config["hyperparams"][a]
        ]
        if diff:
            raise ValueError(f"{out_dir} holds a run with other settings ({', '.join(diff)}); use another out dir")
        config = {**config, "hyperparams": {**old_hp, **config["hyperparams"]}}
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(path, json.dumps(config, indent=2, sort_keys=True).encode())  # another invocation may read it


def pending(specs: list[RunSpec]) -> list[RunSpec]:
    """The specs whose pair file does not exist yet."""
    return [s for s in specs if not pair_csv(s.out_dir, s.name).exists()]


def run_grid(
    specs: list[RunSpec],
    backend: str = "process",
    workers: int = 2,
    ray_address: str | None = None,
    on_epoch: Callable[[int], None] | None = None,
) -> dict[str, list[Row]]:
    """Run the specs; each finished run's rows are written to its pair file at once (and its checkpoint removed).

    ``on_epoch(n)`` is called with the number of epochs finished since its last call (progress bars).
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive int, got {workers!r}")
    results: dict[str, list[Row]] = {}
    seen = {s.name: 0 for s in specs}

    def report(spec: RunSpec, done: int) -> None:
        if on_epoch is not None and done > seen[spec.name]:
            on_epoch(done - seen[spec.name])
        seen[spec.name] = max(seen[spec.name], done)

    def finish(spec: RunSpec, rows: list[Row]) -> None:
        write_rows(pair_csv(spec.out_dir, spec.name), rows)
        results[spec.name] = rows
        checkpoint_path(spec.out_dir, spec.name).unlink(missing_ok=True)
        progress_path(spec.out_dir, spec.name).unlink(missing_ok=True)
        report(spec, spec.epochs)

    def poll(running: list[RunSpec]) -> None:
        for s in running:
            path = progress_path(s.out_dir, s.name)
            if path.exists():
                report(s, len(path.read_text().split()))

    if backend == "serial":
        for s in specs:
            finish(s, run_pair(s))
    elif backend == "process":
        with cf.ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as pool:
            futures = {pool.submit(run_pair, s): s for s in specs}
            todo = set(futures)
            while todo:
                done, todo = cf.wait(todo, timeout=2.0, return_when=cf.FIRST_COMPLETED)
                for fut in done:
                    finish(futures[fut], fut.result())
                poll([futures[f] for f in todo])
    else:
        _run_ray(specs, workers, ray_address, finish, poll)
    return results


def _run_ray(specs, workers, ray_address, finish, poll) -> None:
    import ray

    init: dict[str, Any] = {"ignore_reinit_error": True, "include_dashboard": False}
    if ray_address:
        init["address"] = ray_address
    else:  # a local instance: its workers import this checkout the way the driver does
        init["num_cpus"] = workers
        init["runtime_env"] = {"env_vars": {"PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}}
    started_here = not ray.is_initialized()
    ray.init(**init)
    try:
        remote = ray.remote(num_cpus=1, max_retries=0)(run_pair)
        refs = {remote.remote(s): s for s in specs}
        todo = list(refs)
        while todo:
            done, todo = ray.wait(todo, num_returns=1, timeout=2.0)
            for ref in done:
                finish(refs[ref], ray.get(ref))
            poll([refs[r] for r in todo])
    finally:
        if started_here:
            ray.shutdown()
