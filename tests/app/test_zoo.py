"""rl-zoo3 integration: tiny-budget training for both algorithms, a two-trial Optuna study, enjoy."""

from __future__ import annotations

import glob
import os
import subprocess
import sys
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path

import optuna
import pytest
import yaml

import tests.helpers.toy_nav  # noqa: F401  (registers ToyNav-v0)
import twodrl_envs  # noqa: F401  (registers the Nomad office ids)
from twodrl_zoo import cli, export, zoo
from twodrl_zoo.hyperparams import hyperparams_path
from twodrl_zoo.zoo import (
    GYM_PACKAGES_GROUP,
    ZOO_ALGOS,
    ZOO_SAMPLERS,
    convert_two_dim_params,
    prepare_zoo_argv,
    register_zoo,
    sample_twoda2c_params,
    sample_twodppo_params,
)

ROOT = Path(__file__).resolve().parents[2]
ZOO_ENVS = ["NomadOffice-v0", "NomadOfficeMemorable-v0", "CartPole-v1", "Acrobot-v1"]
ALGOS = ["a2c", "twoda2c", "ppo", "twodppo"]


def run_command(name: str, argv: list[str], monkeypatch) -> None:
    """The installed console command ``name`` (its ``console_scripts`` entry point) with ``argv``."""
    (command,) = entry_points(group="console_scripts", name=name)
    monkeypatch.setattr(sys, "argv", [name, *argv])
    command.load()()


def toy_conf(tmp_path: Path, algo: str) -> Path:
    entry = {
        "n_envs": 2,
        "n_timesteps": 200,
        "policy": "MlpPolicy",
        "gamma": 0.9,
        "n_steps": 5,
        "callback": ["sb3_twodrl.callbacks.NavigationMetricsCallback"],
    }
    if algo.startswith("twod"):
        entry["punishment_gamma"] = 0.1
    if algo.endswith("ppo"):
        entry.update(n_steps=32, batch_size=32, n_epochs=2)
    path = tmp_path / f"{algo}_toy.yml"
    path.write_text(yaml.safe_dump({"ToyNav-v0": entry}))
    return path


def scalar_tags(tb_dir: Path) -> set[str]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    tags: set[str] = set()
    for event_file in glob.glob(str(tb_dir / "**" / "events.out.tfevents.*"), recursive=True):
        acc = EventAccumulator(event_file)
        acc.Reload()
        tags |= set(acc.Tags()["scalars"])
    return tags


def test_the_commands_import_every_env_package_of_the_entry_point_group(tmp_path, monkeypatch):
    (tmp_path / "some_env_package.py").write_text("import gymnasium\ngymnasium.register('SomeEnv-v0', 'x:Y')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    points = [EntryPoint("some_env_package", "some_env_package", GYM_PACKAGES_GROUP)]
    monkeypatch.setattr(zoo, "entry_points", lambda group: points if group == GYM_PACKAGES_GROUP else [])
    import gymnasium

    try:
        assert prepare_zoo_argv(["--algo", "a2c"]) == ["--algo", "a2c"]
        assert "SomeEnv-v0" in gymnasium.registry
    finally:
        gymnasium.registry.pop("SomeEnv-v0", None)
        sys.modules.pop("some_env_package", None)


def test_yaml_covers_the_envs_for_both_algorithms():
    for algo in ALGOS:
        conf = yaml.safe_load(hyperparams_path(algo).read_text())
        for env_id in ZOO_ENVS:
            assert env_id in conf, (algo, env_id)
            names = [next(iter(c)) if isinstance(c, dict) else c for c in conf[env_id]["callback"]]
            assert "sb3_twodrl.callbacks.NavigationMetricsCallback" in names
        assert conf["NomadOffice-v0"]["gamma"] == 0.9
    for algo in ("twoda2c", "twodppo"):
        assert yaml.safe_load(hyperparams_path(algo).read_text())["NomadOffice-v0"]["punishment_gamma"] == 0.1


@pytest.mark.parametrize("algo", ALGOS)
def test_train_tiny_budget_leaves_model_and_tensorboard(algo, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["--algo", algo, "--env", "ToyNav-v0", "--gym-packages", "tests.helpers.toy_nav"]
    argv += ["-conf", str(toy_conf(tmp_path, algo))]
    argv += ["-n", "200", "--eval-freq", "100", "--eval-episodes", "2", "--save-freq", "100", "--log-interval", "1"]
    argv += ["-tb", "tb", "-f", "logs", "--seed", "0", "--device", "cpu"]
    run_command("sb3-twodrl-train", argv, monkeypatch)
    model_path = tmp_path / "logs" / algo / "ToyNav-v0_1" / "ToyNav-v0.zip"
    assert model_path.is_file()
    assert list((tmp_path / "logs" / algo / "ToyNav-v0_1").glob("rl_model_*_steps.zip"))  # --save-freq
    assert (tmp_path / "logs" / algo / "ToyNav-v0_1" / "evaluations.npz").is_file()  # --eval-freq
    register_zoo()
    from rl_zoo3.utils import ALGOS as RL_ZOO_ALGOS

    model = RL_ZOO_ALGOS[algo].load(model_path, device="cpu")
    assert model.num_timesteps >= 200
    tags = scalar_tags(tmp_path / "tb")
    for key in ("goal_rate", "reward_per_step", "shortcut_share", "detour_share", "collision_rate"):
        assert f"rollout/{key}" in tags
    if algo.startswith("twod"):
        assert "train/interest" in tags
    # enjoy replays it (no rendering in tests)
    run_command(
        "sb3-twodrl-enjoy",
        ["--algo", algo, "--env", "ToyNav-v0", "--gym-packages", "tests.helpers.toy_nav", "-n", "20", "--no-render"],
        monkeypatch,
    )
    if algo == "a2c":  # and records a video (rl-zoo3's record_video)
        pytest.importorskip("moviepy")
        record = ["--algo", algo, "--env", "ToyNav-v0", "--gym-packages", "tests.helpers.toy_nav"]
        run_command("sb3-twodrl-enjoy", [*record, "--record", "-o", "videos", "-n", "10"], monkeypatch)
        assert list((tmp_path / "videos").glob("*.mp4"))


@pytest.mark.parametrize("env_id", ["CartPole-v1", "Acrobot-v1", "NomadOffice-v0"])
@pytest.mark.parametrize("algo", ALGOS)
def test_shipped_hyperparams_train(algo, env_id, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["--algo", algo, "--env", env_id, "-n", "64", "--eval-freq", "-1"]
    argv += ["-f", "logs", "--seed", "1", "--device", "cpu"]
    run_command("sb3-twodrl-train", argv, monkeypatch)
    assert (tmp_path / "logs" / algo / f"{env_id}_1" / f"{env_id}.zip").is_file()


@pytest.mark.parametrize("algo", ["a2c", "twoda2c", "twodppo"])
def test_two_trial_optuna_study_with_shared_storage(algo, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    storage = str(tmp_path / "study.log")  # journal file: several machines can share it (or an RDB URL)
    argv = ["--algo", algo, "--env", "ToyNav-v0", "--gym-packages", "tests.helpers.toy_nav"]
    argv += ["-conf", str(toy_conf(tmp_path, algo))]
    argv += ["-optimize", "--n-trials", "2", "-n", "100", "--n-evaluations", "1", "--eval-episodes", "2"]
    argv += ["--sampler", "random", "--pruner", "none", "--no-optim-plots", "--storage", storage]
    argv += ["--study-name", "zoo-test", "-f", "logs", "--seed", "0", "--device", "cpu"]
    run_command("sb3-twodrl-train", argv, monkeypatch)
    journal = optuna.storages.JournalStorage(optuna.storages.journal.JournalFileBackend(storage))
    study = optuna.load_study(study_name="zoo-test", storage=journal)
    assert len(study.trials) == 2
    assert any(t.state == optuna.trial.TrialState.COMPLETE for t in study.trials)
    assert list((tmp_path / "logs" / algo).glob("report_ToyNav-v0_*.csv"))


@pytest.mark.parametrize("sampler", [sample_twoda2c_params, sample_twodppo_params])
def test_two_dim_sampler_space(sampler):
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    trial = study.ask()
    params = sampler(trial, 4, 2, {})
    assert 0.0 <= params["punishment_gamma"] <= 0.99
    assert 0.0 <= params["punishment_gae_lambda"] <= 1.0
    assert params["punishment_weight"] > 0 and params["punishment_vf_coef"] > 0
    assert 0.1 <= params["min_temperature"] <= 10.0
    assert 0.8 <= params["gamma"] < 1.0
    assert "net_arch" in params["policy_kwargs"]
    # the converter maps a stored trial's params to the same constructor arguments (--trial-id)
    assert convert_two_dim_params(trial.params) == params


def test_register_zoo_tables():
    from rl_zoo3.hyperparams_opt import HYPERPARAMS_CONVERTER, HYPERPARAMS_SAMPLER
    from rl_zoo3.utils import ALGOS as RL_ZOO_ALGOS

    register_zoo()
    for key, algo in ZOO_ALGOS.items():
        assert RL_ZOO_ALGOS[key] is algo
        assert HYPERPARAMS_SAMPLER[key] is ZOO_SAMPLERS[key]
        assert HYPERPARAMS_CONVERTER[key] is convert_two_dim_params


@pytest.mark.parametrize(
    ("command", "argv", "blocked", "extra"),
    [
        (cli.train, ["--algo", "twoda2c", "--env", "NomadOffice-v0"], "rl_zoo3", "zoo"),
        (cli.train, ["--algo", "twoda2c", "--env", "NomadOffice-v0"], "pandas", "zoo"),
        (cli.enjoy, ["--algo", "twoda2c", "--env", "NomadOffice-v0"], "rl_zoo3", "zoo"),
        (cli.enjoy, ["--algo", "twoda2c", "--env", "NomadOffice-v0"], "requests", "zoo"),
        (export.main, ["m.zip", "p.onnx", "--format", "onnx"], "onnx", "onnx"),
    ],
)
def test_a_command_without_its_extra_exits_first_naming_it(command, argv, blocked, extra, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, blocked, None)  # import of it raises ImportError, as when not installed
    if blocked == "rl_zoo3":
        for name in [m for m in sys.modules if m.startswith("rl_zoo3.")]:
            monkeypatch.delitem(sys.modules, name)
    with pytest.raises(SystemExit) as exit_info:
        command(argv)
    assert f'pip install "sb3-twodrl[{extra}]"' in str(exit_info.value.code) and blocked in str(exit_info.value.code)
    assert list(tmp_path.iterdir()) == []  # no work started: no logs, no output file


def test_enjoy_record_without_moviepy_says_so(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, "moviepy", None)
    with pytest.raises(SystemExit, match="moviepy not installed: --record needs it, pip install moviepy"):
        cli.enjoy(["--algo", "a2c", "--env", "CartPole-v1", "--record", "-o", "videos"])


def test_enjoy_without_pygame_replays_headless_and_names_the_extra(tmp_path, monkeypatch) -> None:
    """The README's install (the ``zoo`` extra) has no pygame: enjoy replays without a window instead of failing."""
    monkeypatch.chdir(tmp_path)
    argv = [
        "--algo",
        "twoda2c",
        "--env",
        "NomadOffice-v0",
        "-n",
        "64",
        "--eval-freq",
        "-1",
        "-f",
        "logs",
        "--seed",
        "1",
    ]
    run_command("sb3-twodrl-train", [*argv, "--device", "cpu"], monkeypatch)
    code = (
        "import sys; sys.modules['pygame'] = None\n"  # import pygame raises ImportError, as when not installed
        "from twodrl_zoo import cli; cli.enjoy(['--algo', 'twoda2c', '--env', 'NomadOffice-v0', '-n', '20'])"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (
        'pygame not installed: replaying without a window (--no-render); for one, pip install "sb3-twodrl[render]"'
        in (done.stderr)
    )
    assert "Mean reward" in done.stdout


def test_installed_commands_point_at_the_cli() -> None:
    pyproject = (ROOT / "pyproject.toml").read_text()
    for line in (
        'sb3-twodrl-train = "twodrl_zoo.cli:train"',
        'sb3-twodrl-enjoy = "twodrl_zoo.cli:enjoy"',
        'sb3-twodrl-export = "twodrl_zoo.export:main"',
    ):
        assert line in pyproject.splitlines()


@pytest.mark.parametrize(
    ("argv", "added"),
    [
        (
            ["--algo", "twoda2c", "--env", "NomadOffice-v0"],
            ["--conf-file", str(hyperparams_path("twoda2c")), "--num-threads", "1", "--n-eval-envs", "0"],
        ),
        (
            ["--algo", "twoda2c", "--env", "NomadOffice-v0", "--num-threads", "2", "--n-eval-envs", "1"],
            ["--conf-file", str(hyperparams_path("twoda2c"))],
        ),
        (["--algo", "a2c", "--env", "CartPole-v1", "-conf", "mine.yml"], ["--num-threads", "1", "--n-eval-envs", "0"]),
        (["--algo", "dqn", "--env", "CartPole-v1"], ["--num-threads", "1", "--n-eval-envs", "0"]),  # rl-zoo3's file
    ],
)
def test_train_defaults_to_the_packaged_file_one_thread_and_checks_side_by_side(argv, added, monkeypatch):
    import twodrl_zoo.zoo

    seen: list[list[str]] = []
    monkeypatch.setattr(twodrl_zoo.zoo, "run_zoo_entry", lambda prog, argv, entry: seen.append(argv))
    cli.train(argv)
    assert seen == [[*argv, *added]]


def test_enjoy_without_a_screen_replays_headless_and_says_so(tmp_path, monkeypatch) -> None:
    """The README's replay line on a server (no DISPLAY): no window, no pygame warnings, a line saying why."""
    pytest.importorskip("pygame")
    monkeypatch.chdir(tmp_path)
    argv = ["--algo", "twoda2c", "--env", "NomadOffice-v0", "-n", "64", "--eval-freq", "-1", "--seed", "1"]
    run_command("sb3-twodrl-train", [*argv, "--device", "cpu"], monkeypatch)
    code = "from twodrl_zoo import cli; cli.enjoy(['--algo', 'twoda2c', '--env', 'NomadOffice-v0', '-n', '20'])"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "XDG_RUNTIME_DIR")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "no screen (DISPLAY and WAYLAND_DISPLAY unset): replaying without a window (--no-render)" in done.stderr
    assert "XDG_RUNTIME_DIR" not in done.stderr and "Mean reward" in done.stdout
