"""One checkpoint-and-resume scheme for every job: a killed timesteps job resumes with the uninterrupted row (the
epoch jobs' case is in tests/bench/test_experiments.py), and a checkpoint of another run is refused naming the key."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rl_zoo3")

from twodrl_bench import jobs
from twodrl_bench.experiment import Experiment, Job
from twodrl_bench.runner import run_job
from twodrl_bench.spec import load_spec

BUDGET, EVERY = 3000, 1000


def cliff_job(out: Path, **protocol: Any) -> Job:
    """``benchmark/CliffWalking``'s ``twoda2c`` arm, seed 0, at a small budget checkpointed every 1000 timesteps."""
    spec = load_spec("benchmark/CliffWalking")
    spec["protocol"] = {**spec["protocol"], "timesteps": BUDGET, "eval_episodes": 2, "checkpoint_every": EVERY}
    spec["protocol"].update(protocol)
    spec.update(seeds=[0], arms={"twoda2c": spec["arms"]["twoda2c"]})
    (job,) = Experiment.from_spec(spec).jobs(out)
    return job


def without_wall(rows: list[dict[str, Any]]) -> str:
    return json.dumps([{k: v for k, v in row.items() if k != "wall_s"} for row in rows], sort_keys=True)


def _run_and_die(job: Job, die_at_save: int) -> None:
    """Worker that is killed (SIGKILL, no clean-up) when it starts its ``die_at_save``-th checkpoint."""
    original, calls = jobs.save, []

    def dying(*args: Any, **kwargs: Any) -> None:
        calls.append(1)
        if len(calls) == die_at_save:
            os.kill(os.getpid(), signal.SIGKILL)
        original(*args, **kwargs)

    jobs.save = dying
    run_job(job)


def kill_at_second_checkpoint(job: Job) -> None:
    worker = mp.get_context("spawn").Process(target=_run_and_die, args=(job, 2))
    worker.start()
    worker.join(300)
    assert worker.exitcode == -signal.SIGKILL


def test_a_killed_timesteps_job_resumes_with_the_uninterrupted_row(tmp_path) -> None:
    """Killed after its first checkpoint (the Monitor files then hold episodes past it), rerun: the same row."""
    whole = run_job(cliff_job(tmp_path / "whole"))
    killed = cliff_job(tmp_path / "killed")
    kill_at_second_checkpoint(killed)
    assert jobs.checkpoint_path(killed.out_dir, killed.name).exists()
    (done,) = map(int, jobs.progress_path(killed.out_dir, killed.name).read_text().split())
    assert EVERY <= done < 2 * EVERY
    resumed = run_job(killed)
    assert without_wall(resumed) == without_wall(whole)
    assert json.loads(resumed[0]["curve"])[-1][0] == BUDGET and resumed[0]["train_episodes"] > 0
    assert not jobs.checkpoint_path(killed.out_dir, killed.name).exists(), "a finished job leaves no checkpoint"


def test_a_checkpoint_of_another_run_is_refused_naming_the_key(tmp_path) -> None:
    job = cliff_job(tmp_path)
    kill_at_second_checkpoint(job)
    with pytest.raises(ValueError, match=r"another run .*protocol\.eval_episodes: 2 != 3"):
        run_job(cliff_job(tmp_path, eval_episodes=3))


def test_a_checkpoint_that_names_no_run_is_refused(tmp_path) -> None:
    """An older bench's checkpoint (no identity in it) is not resumed as if it were this job's."""
    from stable_baselines3 import A2C

    from twodrl_bench.checkpoint import save_checkpoint

    job = cliff_job(tmp_path)
    save_checkpoint(jobs.checkpoint_path(job.out_dir, job.name), A2C("MlpPolicy", "CartPole-v1"), {"protocol": {}})
    with pytest.raises(ValueError, match="written by an older bench"):
        jobs.resume(job)
