"""The study runner gives the rows of the grid runner of commit 01db862, timings aside.

That grid's rows are made here, on the same machine, by what it ran for each (algo, seed): the epoch job's
training (:func:`twodrl_bench.epochs.train`, the function that grid's ``run_pair`` became) on the settings
01db862's ``specs_from_args`` built (the env's entry of ``<algo>.yml`` read as written, ``--n-envs`` over
it). A committed CSV would not do: rows differ bitwise between machines. The same
comparison against that commit's command itself (``01db862:scripts/reproduce.py``) on
``NomadOfficeMemorable-v0`` is in ``docs/studies.md``.
"""

from __future__ import annotations

import pandas as pd

from tests.helpers.toy_study import ALGOS, ENV, toy_settings, toy_spec
from twodrl_bench.epochs import train
from twodrl_bench.experiment import Experiment
from twodrl_bench.runner import run_study

SEED = 1


def old_rows(settings, out) -> pd.DataFrame:
    rows = []
    for algo in ALGOS:
        arm = {"algo": algo, "settings": str(settings), "override": {"n_envs": 2}}
        protocol = {"epochs": 3, "learn_episodes": 8, "test_episodes": 4}
        spec = {
            "name": algo,
            "env": ENV,
            "gym_packages": ["tests.helpers.toy_nav"],
            "protocol": protocol,
            "seeds": [SEED],
        }
        (job,) = Experiment.from_spec({**spec, "arms": {algo: arm}, "report": "paper"}).jobs(out)
        rows += train(job)
    return pd.DataFrame(rows)


def test_the_runner_on_worker_processes_gives_the_old_grids_rows(tmp_path) -> None:
    settings = toy_settings(tmp_path / "settings")
    old = old_rows(settings, tmp_path / "old")
    folder = run_study(toy_spec(settings, seeds=[SEED]), tmp_path / "new", "process", 2, report=False)
    new = pd.read_csv(folder / "rows.csv")
    assert list(new["arm"]) == list(new["algo"])
    columns = [c for c in old.columns if c != "wall_s"]
    key = ["algo", "seed", "epoch"]
    pd.testing.assert_frame_equal(
        new[columns].sort_values(key).reset_index(drop=True),
        old[columns].sort_values(key).reset_index(drop=True),
        check_exact=True,
    )
