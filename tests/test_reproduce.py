"""The reproduce command line: tiny preset writes CSV, figures and models; resumes; Ray == process."""

from __future__ import annotations

import json

import pandas as pd
import pytest

pytest.importorskip("matplotlib")
pytest.importorskip("yaml")

from sb3_twodrl.hyperparams import hyperparams_path, read_entry
from twodrl_bench import COLUMNS, PRESETS, algo_class, reproduce

ALGOS = ["twoda2c", "a2c"]

ENV = "ToyNavRandom-v0"
SEEDS = ["0", "1"]
COMMON = ["--env", ENV, "--gym-packages", "tests.toy_nav", "--preset", "tiny", "--n-envs", "2", "--seed-list", *SEEDS]
COMMON += ["--algos", *ALGOS, "--no-progress"]
FIGS = ["fig3_goal_rate.png", "fig4_reward_per_step.png", "fig5_route_share.png"]


def without_wall(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=["wall_s"]).sort_values(["algo", "seed", "epoch"]).reset_index(drop=True)


@pytest.fixture(scope="module")
def toy_hp(tmp_path_factory) -> list[str]:
    """``--hyperparams-dir`` of files that give the toy env the packaged NomadOffice-v0 entries."""
    import yaml

    folder = tmp_path_factory.mktemp("hyperparams")
    for algo in ALGOS:
        entry = read_entry(hyperparams_path(algo), "NomadOffice-v0")
        (folder / f"{algo}.yml").write_text(yaml.safe_dump({ENV: entry}))
    return ["--hyperparams-dir", str(folder)]


@pytest.fixture(scope="module")
def process_run(tmp_path_factory, toy_hp):
    out = tmp_path_factory.mktemp("process")
    reproduce.reproduce([*COMMON, *toy_hp, "--out", str(out), "--backend", "process", "--workers", "2"])
    return out


def test_tiny_preset_writes_csv_figures_and_tensorboard(process_run):
    df = pd.read_csv(process_run / "results.csv")
    assert list(df.columns) == COLUMNS
    epochs = PRESETS["tiny"]["epochs"]
    assert len(df) == len(ALGOS) * len(SEEDS) * epochs
    assert sorted(df["algo"].unique()) == sorted(ALGOS)
    assert set(df["epoch"]) == set(range(1, epochs + 1))
    assert df["goal_rate"].between(0, 1).all()
    assert (df["env_steps"].groupby([df["algo"], df["seed"]]).diff().dropna() > 0).all()
    shares = df.dropna(subset=["shortcut_share"])
    assert ((shares["shortcut_share"] + shares["detour_share"]) - 1).abs().max() < 1e-9
    for fig in FIGS:
        assert (process_run / fig).stat().st_size > 1000
    assert "| algorithm |" in (process_run / "summary.md").read_text()
    for algo in ALGOS:
        for seed in SEEDS:
            assert list((process_run / "tb").glob(f"{algo}_seed{seed}_0/events.out.tfevents.*"))
            model = algo_class(algo).load(process_run / "models" / f"{algo}_seed{seed}.zip")
            assert model.predict(model.observation_space.sample())[0] in range(4)
    assert not list((process_run / "checkpoints").glob("*")), "a finished run leaves no checkpoint"


def test_resume_skips_finished_pairs_and_redoes_only_missing(process_run, toy_hp, capsys):
    pairs = sorted((process_run / "pairs").glob("*.csv"))
    stamps = {p: p.stat().st_mtime_ns for p in pairs}
    before = pd.read_csv(process_run / "results.csv")
    # Nothing left to do: no pair is run again, no row is duplicated.
    reproduce.reproduce([*COMMON, *toy_hp, "--out", str(process_run), "--backend", "serial", "--no-plots"])
    assert f"{len(pairs)} of {len(pairs)}" in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in pairs} == stamps
    pd.testing.assert_frame_equal(pd.read_csv(process_run / "results.csv"), before)
    # An interrupted grid: one pair missing. Only it runs again, and it gives the same rows (seeded).
    pair_path = process_run / "pairs" / f"a2c_seed{SEEDS[-1]}.csv"
    pair_path.unlink()
    reproduce.reproduce([*COMMON, *toy_hp, "--out", str(process_run), "--backend", "serial", "--no-plots"])
    assert all(p.stat().st_mtime_ns == stamps[p] for p in pairs if p != pair_path)
    pd.testing.assert_frame_equal(without_wall(pd.read_csv(process_run / "results.csv")), without_wall(before))


def test_resume_refuses_other_protocol(process_run, toy_hp):
    with pytest.raises(ValueError, match="other settings"):
        reproduce.reproduce([*COMMON, *toy_hp, "--out", str(process_run), "--epochs", "5", "--no-plots"])


def test_resume_accepts_an_added_algo(tmp_path, toy_hp):
    base = ["--env", ENV, "--gym-packages", "tests.toy_nav", "--preset", "tiny", "--n-envs", "2", "--seed-list", "0"]
    base += ["--no-progress", "--no-plots", "--backend", "serial", "--out", str(tmp_path), *toy_hp]
    reproduce.reproduce([*base, "--algos", "a2c"])
    reproduce.reproduce([*base, "--algos", *ALGOS])
    assert sorted(pd.read_csv(tmp_path / "results.csv")["algo"].unique()) == sorted(ALGOS)
    assert sorted(json.loads((tmp_path / "config.json").read_text())["hyperparams"]) == sorted(ALGOS)


@pytest.mark.slow  # starts a Ray cluster of worker processes (about 30 s)
def test_ray_backend_gives_the_process_rows(process_run, toy_hp, tmp_path):
    pytest.importorskip("ray")
    # Ray >= 2.x dropped local_mode; a local single-node Ray instance (one CPU) runs the same tasks instead.
    # One (algo, seed) pair keeps the test short; the runs are independent, so this is the backend's whole job.
    base = ["--env", ENV, "--gym-packages", "tests.toy_nav", "--preset", "tiny", "--n-envs", "2", "--no-progress"]
    one = [*base, *toy_hp, "--algos", "twoda2c", "--seed-list", SEEDS[-1], "--out", str(tmp_path), "--no-plots"]
    reproduce.reproduce([*one, "--backend", "ray", "--workers", "1"])
    ray_rows = without_wall(pd.read_csv(tmp_path / "results.csv"))
    process_rows = without_wall(pd.read_csv(process_run / "results.csv"))
    process_rows = process_rows[(process_rows["algo"] == "twoda2c") & (process_rows["seed"] == int(SEEDS[-1]))]
    pd.testing.assert_frame_equal(ray_rows, process_rows.reset_index(drop=True))


def test_env_kwargs_reach_the_envs_and_guard_resume(tmp_path):
    base = ["--env", "NomadOffice-v0", "--preset", "tiny", "--n-envs", "2", "--seed-list", "0", "--algos", "a2c"]
    base += ["--no-progress", "--no-plots", "--backend", "serial", "--out", str(tmp_path)]
    reproduce.reproduce([*base, "--env-kwargs", "observe_odometry:False"])
    model = algo_class("a2c").load(tmp_path / "models" / "a2c_seed0.zip")
    assert model.observation_space.shape == (32,)  # 16 sonar + 16 infrared, no odometry
    assert json.loads((tmp_path / "config.json").read_text())["env_kwargs"] == {"observe_odometry": False}
    with pytest.raises(ValueError, match="env_kwargs"):
        reproduce.reproduce(base)
