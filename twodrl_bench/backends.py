"""Where a study's jobs run: in this process, in local worker processes, or as Ray tasks.

Every backend calls ``fn(job)`` for each job (a picklable job in, rows out) where the job runs and hands
each result to ``on_done(job, rows, machine)`` as soon as it arrives, in the driver; ``machine`` is
:func:`~twodrl_bench.machine.machine_info` of the process that ran the job, taken after it (so with the
torch threads it ran with). This is the only module of the project that starts worker processes or Ray tasks.

Ray: with ``address`` the driver joins that cluster (``ray start --head`` on one node, ``ray start
--address HOST:PORT`` on the others; every node must import ``sb3_twodrl``, ``twodrl_bench`` and the
env packages, and reach the run folder on a shared file system); without it a local Ray instance
with ``workers`` CPUs starts and stops with the study. A task whose worker dies is retried
(:data:`RAY_RETRIES`); an epoch job then resumes from its last checkpoint.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os
import sys
from collections.abc import Callable
from typing import Any

from twodrl_bench.experiment import Job
from twodrl_bench.machine import REPRODUCIBLE_KERNELS, machine_info

BACKENDS = ("process", "ray", "serial")
RAY_RETRIES = 3
"""Retries of a Ray task whose worker process died (a lost node, a killed process); errors are not retried."""

Rows = list[dict[str, Any]]
OnDone = Callable[[Job, Rows, dict[str, Any]], None]


def run_one(fn: Callable[..., Rows], job: Job) -> tuple[Rows, dict[str, Any]]:
    """``fn(job)`` and the machine that ran it (what a worker process or Ray task executes)."""
    rows = fn(job)
    return rows, machine_info()


def run_jobs(
    fn: Callable[..., Rows],
    jobs: list[Job],
    on_done: OnDone,
    backend: str = "process",
    workers: int = 1,
    address: str | None = None,
) -> None:
    """Run ``fn(job)`` for every job on ``backend`` with ``workers`` at a time; ``on_done`` gets each result.

    :raises ValueError: for an unknown backend, a non-positive ``workers``, or ``address`` without Ray
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive int, got {workers!r}")
    if address is not None and backend != "ray":
        raise ValueError(f"address is for the ray backend, got backend {backend!r} with address {address!r}")
    if backend == "serial":
        for job in jobs:
            on_done(job, *run_one(fn, job))
    elif backend == "process":
        with cf.ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as pool:
            futures = {pool.submit(run_one, fn, job): job for job in jobs}
            try:
                for future in cf.as_completed(futures):
                    on_done(futures[future], *future.result())
            except BaseException:  # a failed job or an interrupt: no queued job starts
                for future in futures:
                    future.cancel()
                raise
    else:
        _run_ray(fn, jobs, on_done, workers, address)


def _run_ray(fn: Callable[..., Rows], jobs: list[Job], on_done: OnDone, workers: int, address: str | None) -> None:
    try:
        import ray
    except ImportError:
        raise ValueError("backend 'ray' needs Ray: pip install 'sb3-twodrl[cluster]'") from None
    kernels = {name: os.environ[name] for name in REPRODUCIBLE_KERNELS if name in os.environ}
    init: dict[str, Any] = {"ignore_reinit_error": True, "include_dashboard": False, "log_to_driver": False}
    if address:
        init["address"] = address
        init["runtime_env"] = {"env_vars": kernels}
    else:  # a local instance: its workers import this checkout the way the driver does
        init["num_cpus"] = workers
        init["runtime_env"] = {"env_vars": {"PYTHONPATH": os.pathsep.join(p for p in sys.path if p), **kernels}}
    started_here = not ray.is_initialized()
    ray.init(**init)
    try:
        remote = ray.remote(num_cpus=1, max_retries=RAY_RETRIES, retry_exceptions=False)(run_one)
        refs = {remote.remote(fn, job): job for job in jobs}
        todo = list(refs)
        while todo:
            done, todo = ray.wait(todo, num_returns=1)
            for ref in done:
                on_done(refs[ref], *ray.get(ref))
    finally:
        if started_here:
            ray.shutdown()
