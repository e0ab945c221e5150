"""The study runner: specs are validated with named errors, resolved, run into a folder, resumed and guarded."""

from __future__ import annotations

import json
import multiprocessing as mp
from pathlib import Path

import pandas as pd
import pytest
import yaml

from tests.helpers.toy_study import toy_settings, toy_spec, write_spec
from twodrl_bench import cli
from twodrl_bench.backends import run_jobs
from twodrl_bench.experiment import Experiment
from twodrl_bench.folders import rows_path
from twodrl_bench.runner import guard, run_study
from twodrl_bench.spec import diff, dump, load_spec, packaged_specs, validate

pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def settings(tmp_path_factory) -> Path:
    return toy_settings(tmp_path_factory.mktemp("settings"))


@pytest.fixture(scope="module")
def toy_run(tmp_path_factory, settings) -> Path:
    out = tmp_path_factory.mktemp("run")
    run_study(toy_spec(settings), out, backend="serial", report=False)
    return out


def without_wall(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=["wall_s"]).reset_index(drop=True)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"protocol": {"epochs": 0, "learn_episodes": 8, "test_episodes": 4}}, r"protocol\.epochs must be a positive"),
        ({"protocol": {"epochs": 3}}, r"protocol\.learn_episodes is missing"),
        ({"protocol": {"steps": 3}}, r"protocol must be \{epochs, learn_episodes"),
        ({"protocol": {"epochs": 3, "learn_episodes": 8, "test_episodes": 4, "k": 1}}, r"protocol of epochs takes"),
        ({"seeds": [0, 0]}, "seeds must not repeat"),
        ({"seeds": 5}, "seeds must be a non-empty list"),
        ({"arms": {"x": {"algo": "dqn"}}}, r"arms\.x\.algo must be one of"),
        ({"arms": {"a b": {"algo": "a2c"}}}, "arms names must be"),
        ({"arms": {"x": {"algo": "a2c", "overide": {}}}}, r"arms\.x takes only algo, override and settings"),
        ({"env_kwargs": [1]}, "env_kwargs must be a mapping"),
        ({"colour": "red"}, "fields must be among"),
        ({"report": ""}, "report must be a non-empty string"),
    ],
)
def test_a_bad_spec_is_refused_naming_the_field(settings, change, message) -> None:
    with pytest.raises(ValueError, match=message):
        validate(toy_spec(settings, **change))


def test_a_missing_field_or_spec_is_named(settings) -> None:
    spec = toy_spec(settings)
    del spec["seeds"]
    with pytest.raises(ValueError, match="'seeds' is missing"):
        validate(spec)
    with pytest.raises(ValueError, match=r"neither a \.yml file nor a packaged spec"):
        load_spec("no_such_study")


def test_the_packaged_presets_are_the_papers_protocol() -> None:
    assert {"quick_preset", "paper_preset/NomadOffice-v0", "paper_preset/NomadOfficeMemorable-v0"} <= set(
        packaged_specs()
    )
    quick = Experiment.from_spec("quick_preset").as_dict()
    assert quick["env"] == "NomadOfficeMemorable-v0"
    assert {k: quick["protocol"][k] for k in ("epochs", "learn_episodes", "test_episodes")} == {
        "epochs": 30,
        "learn_episodes": 1000,
        "test_episodes": 100,
    }
    assert quick["seeds"] == [0, 1, 2, 3, 4]
    assert {arm: a["algo"] for arm, a in quick["arms"].items()} == {"twoda2c": "twoda2c", "a2c": "a2c"}
    assert quick["arms"]["a2c"]["hyperparams"]["n_envs"] == 64  # the packaged entry, zoo-only keys dropped
    assert "n_timesteps" not in quick["arms"]["a2c"]["hyperparams"]
    for env in ("NomadOffice-v0", "NomadOfficeMemorable-v0"):
        paper = load_spec(f"paper_preset/{env}")
        assert (paper["env"], paper["protocol"]["epochs"], paper["seeds"]) == (env, 1000, [0, 1, 2, 3, 4])


def test_every_packaged_spec_resolves_and_its_yaml_reads_back_equal() -> None:
    for name in packaged_specs():
        resolved = Experiment.from_spec(name).as_dict()
        assert resolved["name"] == name
        assert diff(yaml.safe_load(dump(resolved)), resolved) == []


def test_a_grid_expands_into_one_arm_per_point(settings) -> None:
    grid = {"algo": "a2c", "settings": str(settings), "points": {"n_envs": [2, 4], "learning_rate": [0.001, 0.003]}}
    spec = validate({**toy_spec(settings, arms={}), "grid": grid})
    assert list(spec["arms"]) == [
        "n_envs=2_learning_rate=0.001",
        "n_envs=2_learning_rate=0.003",
        "n_envs=4_learning_rate=0.001",
        "n_envs=4_learning_rate=0.003",
    ]
    assert spec["arms"]["n_envs=4_learning_rate=0.001"]["override"] == {"n_envs": 4, "learning_rate": 0.001}


def test_diff_names_each_key_path_and_both_values() -> None:
    old = {"arms": {"a2c": {"override": {"ent_coef": 0.05}}}, "env": "E"}
    new = {"arms": {"a2c": {"override": {"ent_coef": 0.5, "n_envs": 4}}}, "env": "E"}
    assert diff(old, new) == ["arms.a2c.override.ent_coef: 0.05 != 0.5", "arms.a2c.override.n_envs: <absent> != 4"]
    assert diff({"x": 1}, {"x": 1.0}) == []
    assert diff({"x": True}, {"x": 1}) == ["x: True != 1"]


def test_a_run_folder_holds_the_resolved_spec_machine_rows_models_and_logs(toy_run, settings) -> None:
    stored = yaml.safe_load((toy_run / "spec.yml").read_text())
    assert stored["arms"]["a2c"]["hyperparams"]["n_envs"] == 2
    assert stored["arms"]["a2c"]["hyperparams"]["gamma"] == 0.9
    assert "ent_coef" in stored["arms"]["a2c"]["hyperparams"] and "vf_coef" in stored["arms"]["a2c"]["defaults"]
    (machine,) = json.loads((toy_run / "machine.json").read_text())  # four jobs, one machine
    assert machine["packages"]["torch"] and machine["torch"]["cpu_capability"] and "MKL_CBWR" in machine["env"]
    assert machine["torch"]["threads"] == 1  # as the epoch jobs ran
    df = pd.read_csv(toy_run / "rows.csv")
    assert list(df.columns[:3]) == ["arm", "env", "algo"]
    assert len(df) == 2 * 2 * 3 and set(df["epoch"]) == {1, 2, 3}
    for arm in ("twoda2c", "a2c"):
        for seed in (0, 1):
            assert rows_path(toy_run, arm, seed).exists()
            assert (toy_run / "models" / f"{arm}_seed{seed}.zip").exists()
            assert list((toy_run / "tb").glob(f"{arm}_seed{seed}_0/events.out.tfevents.*"))
    assert not list((toy_run / "checkpoints").glob("*")), "a finished job leaves no checkpoint"


def test_a_rerun_skips_finished_jobs_and_redoes_a_missing_one_with_the_same_rows(toy_run, settings, capsys) -> None:
    files = sorted((toy_run / "rows").glob("*.csv"))
    stamps = {p: p.stat().st_mtime_ns for p in files}
    before = pd.read_csv(toy_run / "rows.csv")
    run_study(toy_spec(settings), toy_run, backend="serial", report=False)
    assert "4 of 4 jobs already finished" in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in files} == stamps
    missing = rows_path(toy_run, "a2c", 1)
    missing.unlink()
    run_study(toy_spec(settings), toy_run, backend="serial", report=False)
    assert all(p.stat().st_mtime_ns == stamps[p] for p in files if p != missing)
    pd.testing.assert_frame_equal(without_wall(pd.read_csv(toy_run / "rows.csv")), without_wall(before))


def test_a_changed_spec_is_refused_naming_the_changed_key(toy_run, settings) -> None:
    spec = toy_spec(settings)
    spec["arms"]["a2c"]["override"]["ent_coef"] = 0.5
    with pytest.raises(ValueError, match=r"arms\.a2c\.override\.ent_coef: <absent> != 0\.5") as error:
        run_study(spec, toy_run, backend="serial", report=False)
    assert "arms.a2c.hyperparams.ent_coef: 0.05 != 0.5" in str(error.value)
    longer = toy_spec(settings, protocol={"epochs": 4, "learn_episodes": 8, "test_episodes": 4})
    with pytest.raises(ValueError, match=r"protocol\.epochs: 3 != 4"):
        run_study(longer, toy_run, backend="serial", report=False)


def test_an_added_arm_and_seed_run_into_the_folder_and_are_kept(tmp_path, settings) -> None:
    one = toy_spec(settings, seeds=[0], protocol={"epochs": 1, "learn_episodes": 4, "test_episodes": 2})
    only_a2c = {**one, "arms": {"a2c": one["arms"]["a2c"]}}
    run_study(only_a2c, tmp_path, backend="serial", report=False)
    run_study({**one, "seeds": [1]}, tmp_path, backend="serial", report=False)
    stored = yaml.safe_load((tmp_path / "spec.yml").read_text())
    assert sorted(stored["arms"]) == ["a2c", "twoda2c"] and stored["seeds"] == [0, 1]
    df = pd.read_csv(tmp_path / "rows.csv")
    assert sorted(zip(df["arm"], df["seed"], strict=True)) == [("a2c", 0), ("a2c", 1), ("twoda2c", 1)]


def _guard_repeatedly(folder: str, arm: str, settings: str) -> None:
    spec = toy_spec(Path(settings))
    resolved = Experiment.from_spec({**spec, "arms": {arm: spec["arms"][arm]}})
    for _ in range(100):
        guard(folder, resolved)


def test_invocations_on_one_folder_never_read_a_half_written_spec(tmp_path, settings) -> None:
    """Two invocations started together (e.g. one per arm) both read and write ``spec.yml``."""
    ctx = mp.get_context("fork")
    args = [(str(tmp_path), arm, str(settings)) for arm in ("a2c", "twoda2c")]
    workers = [ctx.Process(target=_guard_repeatedly, args=a) for a in args]
    for w in workers:
        w.start()
    for w in workers:
        w.join(60)
    assert [w.exitcode for w in workers] == [0, 0]


def test_backends_refuse_bad_arguments() -> None:
    with pytest.raises(ValueError, match="backend must be one of"):
        run_jobs(dict, [], print, backend="threads")
    with pytest.raises(ValueError, match="workers must be a positive int"):
        run_jobs(dict, [], print, workers=0)
    with pytest.raises(ValueError, match="address is for the ray backend"):
        run_jobs(dict, [], print, backend="process", address="localhost:6379")


def test_the_command_runs_reports_and_shows_status(tmp_path, settings, capsys) -> None:
    spec = toy_spec(settings, seeds=[0], protocol={"epochs": 2, "learn_episodes": 4, "test_episodes": 2})
    path = write_spec(tmp_path / "toy.yml", spec)
    cli.main(["run", str(path), "--out", str(tmp_path / "runs" / "toy"), "--backend", "serial"])
    out = capsys.readouterr().out
    assert "reward per step over epochs 2-2" in out and "summary.md" in out
    assert (tmp_path / "runs" / "toy" / "fig3_goal_rate.png").stat().st_size > 1000
    cli.main(["report", "toy", "--runs", str(tmp_path / "runs"), "--out", str(tmp_path / "results")])
    assert (tmp_path / "results" / "rows.csv").exists() and (tmp_path / "results" / "table.md").exists()
    assert yaml.safe_load((tmp_path / "results" / "spec.yml").read_text())["name"] == "toy"
    capsys.readouterr()
    cli.main(["status", str(tmp_path / "runs")])
    assert "toy (" in (status := capsys.readouterr().out) and "2/2 jobs done" in status
    with pytest.raises(SystemExit):
        cli.parse_args(["run", "quick_preset", "--address", "localhost:6379"])


def test_a_report_by_module_path_taking_records_and_specs(tmp_path, settings, capsys) -> None:
    spec = toy_spec(settings, seeds=[0], protocol={"epochs": 2, "learn_episodes": 4, "test_episodes": 2})
    run_study({**spec, "report": "tests.helpers.toy_records_report"}, tmp_path, "serial")
    assert "4 rows of ['toy'], arms ['a2c', 'twoda2c']" in capsys.readouterr().out
    assert (tmp_path / "table.md").read_text() == "4 rows of ['toy'], arms ['a2c', 'twoda2c']\n"


def test_a_spec_without_a_report_writes_rows_only_and_report_names_the_missing_field(tmp_path, settings) -> None:
    spec = toy_spec(settings, seeds=[0], protocol={"epochs": 1, "learn_episodes": 2, "test_episodes": 2})
    del spec["report"]
    assert validate(spec)["report"] is None
    path = write_spec(tmp_path / "toy.yml", spec)
    folder = tmp_path / "runs" / "toy"
    cli.main(["run", str(path), "--out", str(folder), "--backend", "serial"])
    assert len(pd.read_csv(folder / "rows.csv")) == 2 and not (folder / "table.md").exists()
    cli.main(["run", str(path), "--out", str(folder), "--backend", "serial", "--no-report"])  # resumes: all done
    with pytest.raises(ValueError, match="names no report: add `report: <module>`"):
        cli.main(["report", "toy", "--runs", str(tmp_path / "runs"), "--out", str(tmp_path / "results")])


@pytest.mark.parametrize("study", ["quick_preset", "auto_entropy"])
def test_a_committed_studys_report_rebuilds_its_table_from_its_results_folder(tmp_path, study, capsys) -> None:
    """``sb3-twodrl-bench report <study> --runs results``: a folder without rows files reads its ``rows.csv``."""
    results = Path(__file__).parents[2] / "results"
    cli.main(["report", study, "--runs", str(results), "--out", str(tmp_path)])
    assert (tmp_path / "table.md").read_bytes() == (results / study / "table.md").read_bytes()
