"""The self-tuning entropy study's verdict (results/auto_entropy/preregistration.md) on made-up rows."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import pytest
import yaml

from twodrl_bench.folders import collect, write_rows
from twodrl_bench.reports import Part
from twodrl_bench.reports.auto_entropy import report, verdict
from twodrl_bench.spec import study_of

RULES = {
    "claim": "twod0",
    "against": ["auto98", "auto50"],
    "zero": "zero",
    "fixed": "zero",
    "pairs": {"twod0": "zero"},
    "return": "final_return",
    "return_margin": 2.0,
    "events": "train_events_per_episode",
    "events_margin": 0.02,
    "min_seeds": 10,
}


def part(spec: dict, rows: list[dict], root: Path) -> Part:
    """``spec``'s part with ``rows`` written and read back as the runner collects a run folder's rows."""
    folder = root / spec["name"]
    write_rows(folder / "rows" / "all.csv", rows)
    return Part(spec["name"], study_of(spec["name"])[1], spec, collect(folder), folder)


def office_spec(name: str = "NomadOffice-v0") -> dict:
    """The packaged office spec ``auto_entropy/<name>``."""
    text = resources.files("twodrl_bench").joinpath("specs", "auto_entropy", f"{name}.yml").read_text()
    return yaml.safe_load(text)


def values(**means: tuple[float, float]) -> dict[str, dict[str, list[float]]]:
    """Ten seeds per arm around the given (return, events) means, a small spread so intervals are finite."""
    spread = [(-1) ** i * 0.1 * (i % 3) for i in range(10)]
    return {
        arm: {"return": [r + s for s in spread], "events": [e + s / 100 for s in spread]}
        for arm, (r, e) in means.items()
    }


def test_claim_holds_and_beats_where_the_bonus_matters() -> None:
    text = verdict(values(twod0=(-20, 0.05), auto98=(-30, 0.05), auto50=(-40, 0.05), zero=(-100, 0.2)), RULES)
    assert text == "reference auto98; the claim holds; the interest beats the automatic coefficient"


def test_claim_fails_below_the_margin() -> None:
    text = verdict(values(twod0=(-35, 0.05), auto98=(-30, 0.05), auto50=(-40, 0.05), zero=(-100, 0.2)), RULES)
    assert text == "reference auto98; the claim fails"


def test_claim_fails_on_events_and_reference_is_the_better_target() -> None:
    text = verdict(values(twod0=(-20, 0.2), auto98=(-40, 0.05), auto50=(-20, 0.05), zero=(-100, 0.2)), RULES)
    assert text == "reference auto50; the claim fails"


def test_untested_where_zero_does_as_well() -> None:
    text = verdict(values(twod0=(-20, 0.05), auto98=(-20, 0.05), auto50=(-40, 0.05), zero=(-20, 0.05)), RULES)
    assert text == (
        "reference auto98; untested: the stock algorithm does as well without a bonus as with the automatic one "
        "(the claim's conditions: it holds)"
    )


def test_no_verdict_with_fewer_seeds() -> None:
    few = values(twod0=(-20, 0.05), auto98=(-30, 0.05), auto50=(-40, 0.05), zero=(-100, 0.2))
    few["auto50"] = {k: v[:3] for k, v in few["auto50"].items()}
    assert verdict(few, RULES) == "no verdict: fewer than 10 seeds for auto50"


def test_report_writes_the_table_and_refuses_missing_rules(tmp_path) -> None:
    spec = {"name": "auto_entropy/T", "env": "T-v0", "protocol": {"task": "T"}, "rules": RULES}
    spec["arms"] = {arm: {} for arm in ("zero", "auto98", "auto50", "twod0")}
    rows = [
        {"task": "T", "arm": arm, "seed": seed, "final_return": -10.0 - seed, "train_events_per_episode": 0.1}
        for arm in spec["arms"]
        for seed in range(10)
    ]
    text = report([part(spec, rows, tmp_path / "runs")], tmp_path)
    assert (tmp_path / "table.md").read_text() == text + "\n"
    assert "| twod0 - auto98 | +0.00 [-2.84, +2.84] | +0.000 [+0.000, +0.000] |" in text
    with pytest.raises(ValueError, match="lack"):
        report([part({**spec, "rules": {"claim": "twod0"}}, rows, tmp_path / "bad")], tmp_path)


def test_the_course_table_reads_the_automatic_arms_courses(tmp_path) -> None:
    """Alpha and the entropy fraction at 10%, 50% and 100%, averaged over the seeds that carry a course."""
    spec = {"name": "auto_entropy/T", "env": "T-v0", "protocol": {"task": "T"}, "rules": RULES}
    spec["arms"] = {arm: {} for arm in ("zero", "auto98", "auto50", "twod0")}
    rows = [{"task": "T", "arm": "zero", "seed": 0, "final_return": 0.0, "train_events_per_episode": 0.0}]
    for seed, alpha in ((0, 1.0), (1, 3.0)):
        course = [[100 * (i + 1), alpha * (i + 1), 0.5] for i in range(10)]
        rows.append({**rows[0], "arm": "auto98", "seed": seed, "ent_coef_course": json.dumps(course)})
    text = report([part(spec, rows, tmp_path / "runs")], tmp_path)
    assert "| auto98 | 2.000 [-10.706, 14.706] (n=2) | 0.500 (n=2) | 10.000 [-53.531, 73.531] (n=2)" in text
    assert text.count("| automatic arm |") == 1 and "| zero | 0.000 (n=1)" not in text.split("automatic arm")[1]


def test_learned_counts_enter_the_claim_and_make_a_task_informative() -> None:
    """Return and events within the margins, but the claim learns on 3 seeds against 10: it fails; zero
    learning on 2 against 10 (Wilson intervals apart) makes the office informative on its own."""
    rules = {**RULES, "learned": {"metric": "goal_rate", "at_least": 0.8}}
    vals = values(twod0=(-30, 0.05), auto98=(-30, 0.05), auto50=(-40, 0.05), zero=(-30, 0.05))
    for arm, k in (("twod0", 3), ("auto98", 10), ("auto50", 10), ("zero", 2)):
        vals[arm]["learned"] = [1.0] * k + [0.0] * (10 - k)
    assert verdict(vals, rules) == "reference auto98; the claim fails"
    vals["twod0"]["learned"] = [1.0] * 8 + [0.0] * 2  # 8/10 against 10/10: the intervals overlap
    assert verdict(vals, rules) == "reference auto98; the claim holds"


def _office_rows(arm: str, rps: float, learned: int, move: float = 0.0) -> list[dict[str, object]]:
    """200 epochs of 10 seeds as ``rows.csv`` holds them (text): reward per step ``rps`` (``rps + move``
    over epochs 181-200), the last epoch's goal rate 1 on ``learned`` seeds and 0.3 on the others."""
    rows = []
    for seed in range(400, 410):
        for epoch in range(1, 201):
            value = rps + 0.001 * (seed % 3) + (move if epoch > 180 else 0.0)
            goal = 1.0 if seed - 400 < learned or epoch < 200 else 0.3
            row = {"arm": arm, "env": "NomadOffice-v0", "seed": str(seed), "epoch": str(epoch), "goal_rate": str(goal)}
            row |= {"reward_per_step": str(value), "collision_rate": "0.0", "shortcut_share": "1.0"}
            row |= {"detour_share": "0.0", "env_steps": str(1000 * epoch), "interest_share": ""}
            if "auto" in arm:
                row |= {"ent_coef": str(epoch / 256), "entropy_fraction": "0.5"}  # exact in binary
            else:  # rows.csv's empty cells: the columns only the automatic arms' rows have
                row |= {"ent_coef": "", "entropy_fraction": ""}
            rows.append(row)
    return rows


def test_the_office_is_read_per_run_with_its_learned_rule_extension_and_course(tmp_path) -> None:
    spec = office_spec()
    rows = _office_rows("a2c_ent0", 0.10, 2) + _office_rows("a2c_ent0.05", 0.28, 10)
    rows += _office_rows("a2c_auto0.98", 0.20, 10) + _office_rows("a2c_auto0.5", 0.28, 10)
    rows += _office_rows("twoda2c_ent0", 0.27, 10, move=0.01) + _office_rows("twoda2c_auto0.98", 0.28, 10)
    rows += _office_rows("twoda2c_auto0.5", 0.28, 10)
    text = report([part(spec, rows, tmp_path / "runs")], tmp_path)
    assert "| a2c_ent0 | 0.1010 [0.1004, 0.1016] (n=10) | 0.000 (n=10) | 2/10 [0.06, 0.51] |" in text
    assert "Verdict: reference a2c_auto0.5; the claim holds." in text
    assert "fires for (twoda2c_ent0, a2c_auto0.5); the rule is read on their 1000-epoch rows" in text
    # the course at epochs 20, 100 and 200: alpha 20/256, 100/256, 200/256 on every seed
    assert "| a2c_auto0.5 | 0.078 (n=10) | 0.500 (n=10) | 0.391 (n=10) | 0.500 (n=10) | 0.781 (n=10) |" in text


def test_an_epoch_task_with_another_learned_rule_is_refused(tmp_path) -> None:
    """The office is read with the factorial's per-run metrics, whose learned rule is goal rate >= 0.8."""
    spec = office_spec()
    spec["rules"]["learned"] = {"metric": "goal_rate", "at_least": 0.5}
    with pytest.raises(ValueError, match="rules\\['learned'\\]"):
        report([part(spec, _office_rows("a2c_ent0", 0.1, 2), tmp_path / "runs")], tmp_path)


def test_each_part_is_read_from_its_own_rows(tmp_path) -> None:
    """A public task beside the office, and the office at 200 epochs beside a part with the same env and arm names
    (the registered extension): each part's table holds its own rows only."""
    public = {"name": "auto_entropy/T", "env": "T-v0", "protocol": {"task": "T"}, "rules": RULES}
    public["arms"] = {arm: {} for arm in ("zero", "auto98", "auto50", "twod0")}
    rows = [
        {"task": "T", "env": "T-v0", "arm": arm, "seed": seed, "final_return": -10.0, "train_events_per_episode": 0.1}
        for arm in public["arms"]
        for seed in range(10)
    ]
    office, longer = office_spec(), office_spec()
    longer["name"] = "auto_entropy/NomadOffice-v0_long"
    parts = [part(public, rows, tmp_path), part(office, _office_rows("a2c_ent0", 0.10, 2), tmp_path)]
    parts.append(part(longer, _office_rows("a2c_ent0", 0.20, 10), tmp_path))
    text = report(parts, tmp_path)
    assert "### T\n" in text and "| zero | -10.00 (n=10) |" in text
    ours, theirs = text.split("### NomadOffice-v0\n")[1].split("### NomadOffice-v0_long\n")
    assert "| a2c_ent0 | 0.1010 [0.1004, 0.1016] (n=10) | 0.000 (n=10) | 2/10 [0.06, 0.51] |" in ours
    assert "| a2c_ent0 | 0.2010 [0.2004, 0.2016] (n=10) | 0.000 (n=10) | 10/10 [0.72, 1.00] |" in theirs


def test_the_claim_is_set_against_the_best_fixed_coefficient_once(tmp_path) -> None:
    rows = [
        {"task": "T", "arm": arm, "seed": seed, "final_return": float(seed), "train_events_per_episode": 0.1}
        for arm in ("zero", "best", "auto98", "auto50", "twod0")
        for seed in range(10)
    ]
    spec = {"name": "auto_entropy/T", "env": "T-v0", "protocol": {"task": "T"}, "rules": {**RULES, "fixed": "best"}}
    spec["arms"] = {arm: {} for arm in ("zero", "best", "auto98", "auto50", "twod0")}
    text = report([part(spec, rows, tmp_path / "best")], tmp_path / "best")
    assert text.count("| twod0 - best |") == 1
    spec = {**spec, "rules": RULES}  # fixed is zero, which the pairs already compare with the claim
    text = report([part(spec, rows, tmp_path / "zero")], tmp_path / "zero")
    assert text.count("| twod0 - zero |") == 1
