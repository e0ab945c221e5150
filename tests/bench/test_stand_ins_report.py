"""The stand_ins study's report: rule S1's verdicts, and the table from constructed rows."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from twodrl_bench.reports import Part
from twodrl_bench.reports.stand_ins import report, verdict


@pytest.mark.parametrize(
    ("low", "high", "expected"),
    [(-0.1, 0.1, "agree"), (0.01, 0.14, "agree"), (-0.2, 0.1, "undecided"), (0.05, 0.3, "disagree"),
     (-0.5, -0.2, "disagree"), (float("nan"), float("nan"), "undecided")],
)  # fmt: skip
def test_rule_s1(low: float, high: float, expected: str) -> None:
    assert verdict(low, high, 0.15) == expected


def _rows(arm: str, mujoco: list[int], real: list[int]) -> list[dict]:
    return [
        {"arm": arm, "seed": 6000 + i, "mujoco_success": m, "mujoco_collision": 100 - m, "mujoco_timeout": 0,
         "real_success": r, "real_collision": 100 - r, "real_timeout": 0, "final_success_share": 1.0, "kept_at": 50}
        for i, (m, r) in enumerate(zip(mujoco, real, strict=True))
    ]  # fmt: skip


def test_the_table_pairs_the_robots_by_office(tmp_path: Path) -> None:
    spec = {
        "name": "stand_ins/database",
        "env": "NomadOfficeMemorable-v0",
        "env_kwargs": {"map": "generated:S:{seed}"},
        "rules": {"agree_within": 0.15},
    }
    rows = _rows("twoda2c", [90, 80, 100], [92, 85, 95]) + _rows("a2c", [0, 10, 90], [90, 95, 90])
    text = report([Part(spec["name"], "database", spec, pd.DataFrame(rows), tmp_path)], tmp_path)
    twod = next(line for line in text.splitlines() if line.startswith("| database | twoda2c |"))
    assert "| 3 | 0.900 | 0.907 | -0.007 [" in twod and "| 3/3 |" in twod
    a2c = next(line for line in text.splitlines() if line.startswith("| database | a2c |"))
    assert "| 1/3 |" in a2c and "-0.583" in a2c
    assert "| database | generated:S:6001 | a2c | 10 / 90 / 0 | 95 / 5 / 0 | 1.00 | 50 |" in text
    assert (tmp_path / "table.md").read_text() == text
