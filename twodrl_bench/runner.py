"""The study runner: every (arm, seed) job of an experiment, run on a backend, resumed, guarded.

The runner builds the study object (:class:`twodrl_bench.experiment.Experiment`) from a spec, guards the run
folder with it, asks it for its jobs and runs those without rows on a backend (:mod:`twodrl_bench.backends`),
each by :func:`run_job`: the job interface, ``run(job) -> rows`` of the protocol's module (:mod:`twodrl_bench.epochs`,
:mod:`twodrl_bench.timesteps`), both resumable the same way (:mod:`twodrl_bench.jobs`).

The run folder (:mod:`twodrl_bench.folders`: ``spec.yml``, ``machine.json``, ``rows/``, ``rows.csv``) also
holds what the jobs keep: ``checkpoints/`` (a job without rows resumes from its checkpoint), ``progress/``,
``models/`` and ``tb/`` or ``zoo/``. Running a spec into a folder whose stored experiment differs in what decides
the rows (:meth:`~twodrl_bench.experiment.Experiment.differences`) is refused; arms and seeds may be added.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path
from typing import Any

from twodrl_bench.backends import run_jobs
from twodrl_bench.checkpoint import atomic_write_bytes
from twodrl_bench.experiment import Experiment, Job
from twodrl_bench.folders import collect, read_spec, record_machine, rows_path, write_rows
from twodrl_bench.spec import Spec, dump

Row = dict[str, Any]


def run_job(job: Job) -> list[Row]:
    """The rows of ``job``, by its protocol's module (resuming its checkpoint)."""
    return importlib.import_module(job.protocol.module).run(job)


def guard(folder: str | Path, experiment: Experiment) -> Experiment:
    """The experiment ``folder`` holds after this run (its stored one merged with ``experiment``), stored there.

    :raises ValueError: naming each differing key path and both values, if the stored experiment differs in
        what decides the rows
    """
    stored = read_spec(folder)
    if stored is not None:
        previous = Experiment.from_resolved(stored)
        differences = experiment.differences(previous)
        if differences:
            raise ValueError(
                f"{folder} holds runs of another spec; use another --out or the stored spec. Differences "
                f"(stored != new): " + "; ".join(differences)
            )
        experiment = experiment.merged(previous)
    atomic_write_bytes(Path(folder) / "spec.yml", dump(experiment.as_dict()).encode())
    return experiment


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
    experiment = Experiment.from_spec(spec)
    folder = Path(out) if out is not None else default_folder(experiment.name)
    todo = experiment.jobs(folder, arms)
    folder.mkdir(parents=True, exist_ok=True)
    guard(folder, experiment)
    for package in experiment.gym_packages:
        importlib.import_module(package)
    pending = [job for job in todo if not rows_path(folder, job.arm_name, job.seed).exists()]
    total = len(todo)
    if len(pending) < total:
        print(f"resuming {folder}: {total - len(pending)} of {total} jobs already finished")
    done = [total - len(pending)]

    def on_done(job: Job, rows: list[Row], machine: dict[str, Any]) -> None:
        write_rows(rows_path(folder, job.arm_name, job.seed), rows)
        record_machine(folder, machine)
        done[0] += 1
        print(f"[{done[0]}/{total}] {job.arm_name} seed {job.seed}: {len(rows)} rows", flush=True)

    run_jobs(run_job, pending, on_done, backend, workers or os.cpu_count() or 1, address)
    collect(folder)
    if report and experiment.report is not None:
        from twodrl_bench.reports import report_run

        report_run(folder)
    elif report:
        print(f"{folder / 'rows.csv'}: the rows (the spec names no report)")
    return folder
