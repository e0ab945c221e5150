"""The train and enjoy commands: one-line errors for what would fail deep in rl-zoo3; enjoy replays from the start."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

pytest.importorskip("rl_zoo3")

import twodrl_envs  # noqa: F401  (registers the Nomad IDs)
from twodrl_zoo.cli import check_command_line, replay_options
from twodrl_zoo.hyperparams import derived_settings, hyperparams_path, read_entry, resolve
from twodrl_zoo.zoo import dict_options


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--env", "NomadOfice-v0"], "env 'NomadOfice-v0' is not registered; did you mean 'NomadOffice-v0'?"),
        (["--env", "NomadOffice-v0", "--env-kwargs", "map:three_rooms.json"], """map:'"my_office.json"'"""),
        (["--env", "NomadOffice-v0", "--env-kwargs", "map:'nope.json'"], "nope.json does not exist"),
        (
            ["--env", "NomadOffice-v0", "-n", "-1000"],
            "-n/--n-timesteps must be a positive number of steps, got '-1000'",
        ),
        (["--env", "NomadOffice-v0", "--n-timesteps=0"], "must be a positive number of steps, got '0'"),
        (
            ["--env", "NomadOfficeMemorable-v0", "--env-kwargs", "database:'gone.npz'"],
            f"{Path('gone.npz').resolve()} does not exist: record one with `sb3-twodrl-record-database",
        ),
    ],
)
def test_a_bad_command_line_exits_with_one_line_naming_it(argv: list[str], message: str) -> None:
    with pytest.raises(SystemExit) as stop:
        check_command_line("sb3-twodrl-train", ["--algo", "twoda2c", *argv])
    text = str(stop.value.code)
    assert text.startswith("sb3-twodrl-train: ") and message in text and "\n" not in text


def _run_folder(root: Path, env_kwargs: dict) -> None:
    folder = root / "logs" / "twoda2c" / "NomadOffice-v0_1" / "NomadOffice-v0"
    folder.mkdir(parents=True)
    (folder / "args.yml").write_text(yaml.dump({"env_kwargs": env_kwargs}))


def test_enjoy_replays_with_the_task_s_test_options_under_the_user_s(tmp_path: Path) -> None:
    _run_folder(tmp_path, {"map": "generated:S:3"})
    argv = ["--algo", "twoda2c", "--env", "NomadOffice-v0", "-f", str(tmp_path / "logs")]
    derived = derived_settings("NomadOffice-v0", {"map": "generated:S:3"})
    assert derived is not None and derived.env_kwargs["starts"] == "uniform"  # what training used
    _, given = dict_options(replay_options(argv))
    assert given["--env-kwargs"] == {"map": "generated:S:3", **derived.eval_env_kwargs}
    assert given["--env-kwargs"]["starts"] == "map"
    _, given = dict_options(replay_options([*argv, "--env-kwargs", "max_episode_steps:50"]))
    assert given["--env-kwargs"] == {"map": "generated:S:3", "starts": "map", "max_episode_steps": 50}


def test_enjoy_leaves_a_run_of_the_paper_s_office_as_trained(tmp_path: Path) -> None:
    _run_folder(tmp_path, {})
    argv = ["--algo", "twoda2c", "--env", "NomadOffice-v0", "-f", str(tmp_path / "logs")]
    assert replay_options(argv) == argv


def test_one_precedence_the_written_entry_the_task_the_user() -> None:
    entry = {**read_entry(Path("twodrl_zoo/hyperparams/twoda2c.yml"), "NomadOffice-v0"), "env_kwargs": {"a": 1}}
    derived = derived_settings("NomadOffice-v0", {"map": "generated:L:3"})
    assert derived is not None
    resolved = resolve(entry, derived, {"gamma": 0.5}, {"map": "generated:L:3", "starts": "map"}, {"b": 2})
    assert resolved.entry["gamma"] == 0.5 and resolved.entry["ent_coef"] == derived.hyperparams["ent_coef"] != 0.05
    assert resolved.entry["n_envs"] == 64 and resolved.entry["env_kwargs"] == resolved.env_kwargs
    assert resolved.env_kwargs == {"a": 1, **derived.env_kwargs, "map": "generated:L:3", "starts": "map"}
    assert resolved.eval_env_kwargs == {"a": 1, "map": "generated:L:3", **derived.eval_env_kwargs, "b": 2}
    # env options a --hyperparams gives are the user's too, under --env-kwargs
    by_hyperparams = resolve(entry, derived, {"env_kwargs": {"c": 3, "starts": "map"}}, {"starts": "uniform"})
    assert by_hyperparams.env_kwargs == {"a": 1, **derived.env_kwargs, "c": 3, "starts": "uniform"}


def test_the_env_states_facts_the_recipe_decides_the_episodes() -> None:
    """The env's task facts hold no episode options; the recipe gives training exploring starts and tests the map's
    start, both with the map's time limit."""
    from twodrl_zoo.hyperparams import task_facts
    from twodrl_zoo.recipe import derive

    facts = task_facts("NomadOffice-v0", {"map": "generated:M:3"})
    assert facts is not None and not any(isinstance(value, dict) for value in facts.values())
    assert facts["time_limit"] == max(300, 3 * facts["farthest_start"])
    derived = derive(facts)
    assert derived.env_kwargs["starts"] == "uniform" and derived.eval_env_kwargs["starts"] == "map"
    assert (
        derived.env_kwargs["max_episode_steps"] == derived.eval_env_kwargs["max_episode_steps"] == facts["time_limit"]
    )


def test_export_help_is_plain_text(capsys: pytest.CaptureFixture[str]) -> None:
    from twodrl_zoo.export import main

    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "--input-stage" in out and not any(markup in out for markup in ("``", ":func:", ":class:", "::"))


@pytest.mark.parametrize("env_kwargs", [{"map": "generated:S:3"}, None], ids=["derived", "paper's office"])
@pytest.mark.parametrize(
    ("options", "factor"),
    [({}, 2), ({"eval_freq": -1}, 1), ({"n_timesteps": 5000}, 1), ({"hyperparams": {"n_timesteps": 5000}}, None)],
)
def test_the_budget_is_a_ceiling_twice_as_long_only_where_checks_stop_training(
    tmp_path: Path, env_kwargs: dict | None, options: dict, factor: int | None
) -> None:
    """The derived budget, and the paper's office's packaged one (the README's first command), alike."""
    import argparse

    from twodrl_zoo.manager import CEILING, ExperimentManager
    from twodrl_zoo.zoo import register_zoo

    register_zoo()
    derived = derived_settings("NomadOffice-v0", env_kwargs)
    written = int(float(read_entry(hyperparams_path("twoda2c"), "NomadOffice-v0")["n_timesteps"]))
    base = written if derived is None else derived.hyperparams["n_timesteps"]
    assert CEILING == 2 and (derived is None) == (env_kwargs is None)
    manager = ExperimentManager(
        argparse.Namespace(),
        "twoda2c",
        "NomadOffice-v0",
        str(tmp_path),
        env_kwargs=env_kwargs,
        config=str(hyperparams_path("twoda2c")),
        **options,
    )
    read, _ = manager.read_hyperparameters()  # the packaged entry under the derived settings, as train reads it
    assert read["n_timesteps"] == (5000 if factor is None else factor * base)
    assert read["policy"] == "MlpPolicy" and read["gamma"] == (0.9 if derived is None else derived.hyperparams["gamma"])


def test_the_bench_s_options_a_resolved_entry_as_it_is_and_a_monitor_per_env(tmp_path: Path) -> None:
    """``entry``: no file read and nothing derived over it, so no ceiling though checks run; ``batched=False``:
    rl-zoo3's envs, a ``Monitor`` file per env, where the default makes one batch under one ``VecMonitor``."""
    import argparse

    from stable_baselines3.common.vec_env import DummyVecEnv

    from twodrl_zoo.manager import ExperimentManager
    from twodrl_zoo.zoo import register_zoo

    register_zoo()
    kwargs = {"map": "generated:S:3"}
    written = read_entry(Path("twodrl_zoo/hyperparams/twoda2c.yml"), "NomadOffice-v0")
    entry = resolve(written, derived_settings("NomadOffice-v0", kwargs), {"n_envs": 2}, kwargs).entry
    monitors = {}
    for batched in (False, True):
        folder = tmp_path / str(batched)
        manager = ExperimentManager(
            argparse.Namespace(), "twoda2c", "NomadOffice-v0", str(folder), entry=entry, batched=batched
        )
        hyperparams, saved = manager.read_hyperparameters()
        assert hyperparams == entry and list(saved) == sorted(entry) and manager.custom_hyperparams is None
        model, _ = manager.setup_experiment()
        assert manager.n_timesteps == entry["n_timesteps"] and manager.env_kwargs == entry["env_kwargs"]
        assert isinstance(model.get_env(), DummyVecEnv) == (not batched)
        monitors[batched] = sorted(p.name for p in Path(manager.save_path).glob("*monitor.csv"))
        model.get_env().close()
    assert monitors == {False: ["0.monitor.csv", "1.monitor.csv"], True: ["monitor.csv"]}
