"""The study runner: every (arm, seed) job of a spec, run on a backend, resumed, guarded.

A job is one (arm, seed) of a resolved spec (:mod:`twodrl_bench.spec`); its function is chosen by
the protocol: :func:`twodrl_bench.epochs.run_job` (the paper's epochs) or
``twodrl_bench.timesteps.run_job`` (a budget of timesteps and a final evaluation), both
``run_job(arm, env, env_kwargs, protocol, seed, out_dir, gym_packages) -> rows``.

The run folder (:mod:`twodrl_bench.folders`: ``spec.yml``, ``machine.json``, ``rows/``, ``rows.csv``) also
holds what the jobs keep: ``checkpoints/`` (a job without rows resumes from its checkpoint), ``progress/``,
``models/`` and ``tb/``. Running a spec into a folder whose stored spec differs in what decides the rows
(:func:`twodrl_bench.spec.guard_diff`) is refused; arms and seeds may be added.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from twodrl_bench.backends import run_jobs
from twodrl_bench.checkpoint import atomic_write_bytes
from twodrl_bench.folders import collect, read_spec, record_machine, rows_path, write_rows
from twodrl_bench.spec import Spec, dump, guard_diff, load_spec, merge, resolve, validate

Row = dict[str, Any]


def job_function(protocol: dict[str, Any]) -> Callable[..., list[Row]]:
    """The job function of ``protocol``: epochs or timesteps."""
    module = "twodrl_bench.epochs" if "epochs" in protocol else "twodrl_bench.timesteps"
    return importlib.import_module(module).run_job


def guard(folder: str | Path, resolved: Spec) -> Spec:
    """The spec ``folder`` holds after this run (its stored spec merged with ``resolved``), stored there.

    :raises ValueError: naming each differing key path and both values, if the stored spec differs in
        what decides the rows
    """
    stored = read_spec(folder)
    if stored is not None:
        differences = guard_diff(stored, resolved)
        if differences:
            raise ValueError(
                f"{folder} holds runs of another spec; use another --out or the stored spec. Differences "
                f"(stored != new): " + "; ".join(differences)
            )
        resolved = merge(stored, resolved)
    atomic_write_bytes(Path(folder) / "spec.yml", dump(resolved).encode())
    return resolved


def pending_jobs(resolved: Spec, folder: str | Path, arms: list[str] | None = None) -> list[dict[str, Any]]:
    """The job arguments of every (arm, seed) of ``resolved`` (only ``arms`` if given) without a rows file."""
    jobs = []
    for name in arms or resolved["arms"]:
        arm = resolved["arms"][name]
        for seed in resolved["seeds"]:
            if rows_path(folder, name, seed).exists():
                continue
            jobs.append(
                {
                    "arm": {"name": name, "algo": arm["algo"], "hyperparams": arm["hyperparams"]},
                    "env": resolved["env"],
                    "env_kwargs": resolved["env_kwargs"],
                    "protocol": resolved["protocol"],
                    "seed": seed,
                    "out_dir": str(folder),
                    "gym_packages": resolved["gym_packages"],
                }
            )
    return jobs


def default_folder(name: str) -> Path:
    return Path("runs") / name


def run_study(
    spec: str | Path | Spec,
    out: str | Path | None = None,
    backend: str = "process",
    workers: int | None = None,
    address: str | None = None,
    report: bool = True,
    arms: list[str] | None = None,
) -> Path:
    """Run (or resume) every job of ``spec`` (a packaged name, a path or a spec mapping) into ``out``; the folder.

    ``arms``: run only these arms' jobs (the folder's spec still records every arm of ``spec``).

    Each finished job's rows are written at once; at the end ``rows.csv`` collects them and, with ``report`` and
    a spec that names one, the study's report (:func:`twodrl_bench.reports.report_study`) reads the run folders.
    """
    resolved = resolve(validate(spec) if isinstance(spec, dict) else load_spec(spec))
    unknown = sorted(set(arms or []) - set(resolved["arms"]))
    if unknown:
        raise ValueError(f"arms must be among the spec's {list(resolved['arms'])}, got {unknown}")
    folder = Path(out) if out is not None else default_folder(resolved["name"])
    folder.mkdir(parents=True, exist_ok=True)
    guard(folder, resolved)
    for package in resolved["gym_packages"]:
        importlib.import_module(package)
    jobs = pending_jobs(resolved, folder, arms)
    total = len(arms or resolved["arms"]) * len(resolved["seeds"])
    if len(jobs) < total:
        print(f"resuming {folder}: {total - len(jobs)} of {total} jobs already finished")
    done = [total - len(jobs)]

    def on_done(job: dict[str, Any], rows: list[Row], machine: dict[str, Any]) -> None:
        write_rows(rows_path(folder, job["arm"]["name"], job["seed"]), rows)
        record_machine(folder, machine)
        done[0] += 1
        print(f"[{done[0]}/{total}] {job['arm']['name']} seed {job['seed']}: {len(rows)} rows", flush=True)

    run_jobs(job_function(resolved["protocol"]), jobs, on_done, backend, workers or os.cpu_count() or 1, address)
    collect(folder)
    if report and resolved["report"] is not None:
        from twodrl_bench.reports import report_run

        report_run(folder)
    elif report:
        print(f"{folder / 'rows.csv'}: the rows (the spec names no report)")
    return folder
