"""The one checkpoint-and-resume scheme of every job (:mod:`twodrl_bench.epochs`, :mod:`twodrl_bench.timesteps`).

Both protocols' jobs keep their learning run resumable the same way: at a clean boundary (a rollout's
start) they save a checkpoint (:func:`save`: the whole algorithm, its envs, every generator and the job's own
state, :mod:`twodrl_bench.checkpoint`); a job that finds one continues from it (:func:`resume`) if the checkpoint
was written by the same run (:meth:`~twodrl_bench.experiment.Job.identity`) and gives the rows an uninterrupted
job gives (``wall_s`` aside); a finished job removes it (:func:`finish`).

A job writes under its ``out_dir``: ``checkpoints/<job>.pkl``, ``progress/<job>.txt`` (what it has done, read
by ``sb3-twodrl-bench status``) and ``models/<job>.zip``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from stable_baselines3.common.base_class import BaseAlgorithm

from twodrl_bench.checkpoint import load_checkpoint, save_checkpoint
from twodrl_bench.experiment import Job
from twodrl_bench.spec import diff


def checkpoint_path(out_dir: str | Path, name: str) -> Path:
    return Path(out_dir) / "checkpoints" / f"{name}.pkl"


def model_path(out_dir: str | Path, name: str) -> Path:
    return Path(out_dir) / "models" / f"{name}.zip"


def progress_path(out_dir: str | Path, name: str) -> Path:
    """One line per unit of progress (an epoch, a checkpoint's timesteps) of a running job."""
    return Path(out_dir) / "progress" / f"{name}.txt"


def resume(job: Job) -> tuple[BaseAlgorithm, dict[str, Any], dict[str, Any]] | None:
    """The model, generator states and job state of ``job``'s checkpoint; None if it has none.

    :raises ValueError: naming each differing key, if the checkpoint was written by another run
    """
    path = checkpoint_path(job.out_dir, job.name)
    if not path.exists():
        return None
    model, rng, state = load_checkpoint(path)
    if "identity" not in state:
        raise ValueError(f"{path} was written by an older bench (it names no run): remove it to start the job over")
    differences = diff(state.pop("identity"), job.identity())
    if differences:
        raise ValueError(f"{path} was written by another run (stored != new): " + "; ".join(differences))
    return model, rng, state


def save(job: Job, model: BaseAlgorithm, state: dict[str, Any]) -> None:
    """Checkpoint ``model`` (with its envs and the generators) and the job's ``state``, with the job's identity."""
    save_checkpoint(checkpoint_path(job.out_dir, job.name), model, {**state, "identity": job.identity()})


def finish(job: Job) -> None:
    """Remove what a finished job no longer needs: its checkpoint and progress."""
    checkpoint_path(job.out_dir, job.name).unlink(missing_ok=True)
    progress_path(job.out_dir, job.name).unlink(missing_ok=True)
