"""The train command's last words: one verdict per run, the export line of its own run, and export's warning."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

pytest.importorskip("rl_zoo3")

from twodrl_zoo.cli import train, verdict
from twodrl_zoo.export import unlearned_warning
from twodrl_zoo.manager import CHECKS_FILE


def _record(rates: list[float], learned: bool = False, episodes: int = 20, vary: bool = False) -> dict:
    checks = [{"timesteps": 25_000 * (i + 1), "goal_rate": r, "mean_return": -1.0} for i, r in enumerate(rates)]
    return {
        "checks": checks,
        "passed": any(r >= 0.8 for r in rates),
        "learned_at": checks[-1]["timesteps"] if learned else None,
        "num_timesteps": 25_000 * len(rates),
        "threshold": 0.8,
        "check_episodes": episodes,
        "readings_vary": vary,
    }


@pytest.mark.parametrize(
    ("rates", "learned", "final", "starts", "never"),
    [
        ([0.2, 0.8, 1.0], True, 1.0, "learned", ("NOT", "vary")),
        ([0.2, 0.8, 0.85], True, 0.65, "the goal checks reached 0.8", ("learned", "NOT")),
        ([0.0, 0.0, 0.0], False, 0.0, "NOT learned: no goal check reached 0.8", ("vary",)),
        ([0.4, 0.6], False, 0.9, "NOT learned", ("vary",)),
    ],
)
def test_one_verdict_that_never_contradicts_itself(
    rates: list[float], learned: bool, final: float, starts: str, never: tuple[str, ...]
) -> None:
    text = verdict(final, _record(rates, learned))
    assert text.startswith(starts) and "\n" not in text
    assert not any(word in text for word in never)


def test_a_policy_learned_on_recorded_readings_is_not_promised_to_the_robot() -> None:
    text = verdict(1.0, _record([0.9, 1.0], learned=True, vary=True))
    assert text.startswith("learned on the recorded readings") and "robot" in text and "may be lower" in text


def test_export_warns_only_of_a_run_whose_checks_never_passed(tmp_path: Path) -> None:
    model = tmp_path / "NomadOffice-v0.zip"
    assert unlearned_warning(model) is None  # no record: a model trained elsewhere
    (tmp_path / CHECKS_FILE).write_text(json.dumps(_record([0.0, 0.4])))
    warning = unlearned_warning(model)
    assert warning is not None and "no goal check of this run passed" in warning and "0.40 < 0.8" in warning
    (tmp_path / CHECKS_FILE).write_text(json.dumps(_record([0.0, 0.8])))
    assert unlearned_warning(model) is None


def _train(folder: Path, *more: str, capsys: pytest.CaptureFixture[str]) -> str:
    argv = ["--algo", "twoda2c", "--env", "NomadOffice-v0", "--env-kwargs", "map:'generated:S:3'", "-n", "2560"]
    train([*argv, "-f", str(folder / "logs"), "--eval-freq", "1280", "--seed", "1", *more])
    return capsys.readouterr().out


def test_a_second_run_in_one_folder_reports_and_exports_its_own_model(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    for run in (1, 2):
        out = _train(tmp_path, capsys=capsys)
        (line,) = re.findall(r"^sb3-twodrl-train: export: (.*)$", out, re.MULTILINE)
        assert f"NomadOffice-v0_{run}/NomadOffice-v0.zip" in line
    export = shlex.split(line)
    assert export[:2] == ["sb3-twodrl-export", str(tmp_path / "logs/twoda2c/NomadOffice-v0_2/NomadOffice-v0.zip")]
    assert export[export.index("--env-kwargs") + 1] == 'map:"generated:S:3"'  # rl-zoo3's literal, as typed


def test_with_uuid_the_report_is_of_the_run_trained(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    out = _train(tmp_path, "--uuid", capsys=capsys)
    (line,) = re.findall(r"^sb3-twodrl-train: export: (\S+ \S+)", out, re.MULTILINE)
    model = Path(line.split()[1])
    assert model.is_file() and re.fullmatch(r"NomadOffice-v0_1_[0-9a-f-]+", model.parent.name)
    assert re.search(r"^sb3-twodrl-train: goal rate \d\.\d\d \(\d+ of 20", out, re.MULTILINE)


def test_a_check_s_episodes_run_side_by_side_with_the_checks_of_one_env_at_a_time(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """On a batched env a check's episodes run in as many envs (one policy call per step for all); on the exact
    readings of the simulator they are the episodes one env at a time runs (``--n-eval-envs 1``, rl-zoo3's)."""
    monkeypatch.chdir(tmp_path)
    records = []
    for more in ((), ("--n-eval-envs", "1")):
        folder = tmp_path / str(len(records))
        argv = ["--algo", "twoda2c", "--env", "NomadOffice-v0", "--env-kwargs", "map:'generated:S:3'", "-n", "12800"]
        train([*argv, "-f", str(folder / "logs"), "--eval-freq", "3200", "--seed", "1", *more])
        (path,) = folder.glob(f"logs/twoda2c/*/{CHECKS_FILE}")
        records.append(json.loads(path.read_text()))
    assert [record["check_envs"] for record in records] == [5, 1]
    assert len(records[0]["checks"]) == 4 and records[0]["checks"] == records[1]["checks"]
    capsys.readouterr()
