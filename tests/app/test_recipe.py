"""The settings rule's switches (twodrl_zoo.recipe): the progress signal's sizes and the checks of varying readings,
by revision; the train command applies the current one, the committed studies theirs."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from twodrl_zoo.recipe import LONG_MOVES, PROGRESS, REVISION, VARYING_CHECK_EPISODES, derive


def _facts(moves: int, on_lattice: bool = True, varying: bool = False) -> dict:
    return {
        "shortest_path": moves,
        "farthest_start": moves + 5,
        "on_lattice": on_lattice,
        "varying_readings": varying,
        "time_limit": 300,
    }


@pytest.mark.parametrize("moves", [10, 30, 57, LONG_MOVES, LONG_MOVES + 1, 150])
def test_revision_2_gives_the_progress_signal_on_every_size_revision_1_beyond_80_moves(moves: int) -> None:
    assert REVISION == 2
    assert derive(_facts(moves)).env_kwargs["progress"] == PROGRESS
    assert ("progress" in derive(_facts(moves), revision=1).env_kwargs) == (moves > LONG_MOVES)
    assert "progress" not in derive(_facts(moves, on_lattice=False)).env_kwargs  # no lattice, no such option
    assert ("ent_coef" in derive(_facts(moves)).hyperparams) == (moves > LONG_MOVES)  # unchanged by revision


@pytest.mark.parametrize("varying", [True, False])
def test_varying_readings_get_checks_as_long_as_the_final_test(varying: bool) -> None:
    derived = derive(_facts(40, varying=varying))
    assert derived.check_episodes == (VARYING_CHECK_EPISODES if varying else None) and VARYING_CHECK_EPISODES == 20
    assert ("goal checks of 20 episodes" in derived.note) == varying
    assert derive(_facts(40, varying=varying), revision=1).check_episodes is None


@pytest.mark.parametrize("revision", [0, 3, "2", None])
def test_an_unknown_revision_is_named(revision: object) -> None:
    with pytest.raises(ValueError, match=f"revision must be one of \\(1, 2\\), got {revision!r}"):
        derive(_facts(40), revision=revision)  # type: ignore[arg-type]


@pytest.mark.parametrize(("given", "expected"), [(5, 20), (8, 8)])
def test_the_command_checks_a_database_with_20_episodes_unless_the_user_says_otherwise(
    tmp_path: Path, given: int, expected: int
) -> None:
    pytest.importorskip("rl_zoo3")
    import twodrl_envs  # noqa: F401
    from twodrl_envs.memorable.database import save_database
    from twodrl_envs.memorable.recording import record_database
    from twodrl_zoo.hyperparams import hyperparams_path
    from twodrl_zoo.manager import ExperimentManager
    from twodrl_zoo.zoo import register_zoo

    register_zoo()
    database = tmp_path / "db.npz"
    save_database(record_database(2, map="generated:S:3", seed=0), database)
    options = {"map": "generated:S:3", "database": str(database)}
    manager = ExperimentManager(
        argparse.Namespace(),
        "twoda2c",
        "NomadOfficeMemorable-v0",
        str(tmp_path),
        env_kwargs=options,
        config=str(hyperparams_path("twoda2c")),
        n_eval_episodes=given,
    )
    assert manager.n_eval_episodes == expected
    assert manager.env_kwargs["progress"] == PROGRESS
