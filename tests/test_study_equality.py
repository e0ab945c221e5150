"""The study runner gives the rows of the grid runner of commit 01db862, timings aside.

That grid's rows are made here, on the same machine, by what it ran for each (algo, seed):
:func:`twodrl_bench.epochs.run_pair` (the same function) on a :class:`~twodrl_bench.protocol.RunSpec`
built as 01db862's ``specs_from_args`` built it (the env's entry of ``<algo>.yml`` by ``load_hyperparams``,
``--n-envs`` over it). A committed CSV would not do: rows differ bitwise between machines. The same
comparison against that commit's command itself (``scripts/reproduce.py`` there) on
``NomadOfficeMemorable-v0`` is in ``docs/studies.md``.
"""

from __future__ import annotations

import pandas as pd

from tests.toy_study import ALGOS, ENV, toy_settings, toy_spec
from twodrl_bench.epochs import run_pair
from twodrl_bench.protocol import RunSpec, load_hyperparams
from twodrl_bench.runner import run_study

SEED = 1


def old_rows(settings, out) -> pd.DataFrame:
    rows = []
    for algo in ALGOS:
        hyperparams = {**load_hyperparams(settings / f"{algo}.yml", ENV), "n_envs": 2}
        spec = RunSpec(ENV, algo, SEED, 3, 8, 4, hyperparams, str(out), gym_packages=["tests.toy_nav"])
        rows += run_pair(spec)
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
