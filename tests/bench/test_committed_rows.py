"""The README's main study rerun gives the committed rows (issue 43): its first epoch, seed 0, both algorithms.

The bench runs MKL's reproducible kernels (``MKL_CBWR=COMPATIBLE``, :mod:`twodrl_bench.machine`), but kernels outside
MKL still follow the CPU's instruction set: the test runs where the CPU is of the recording kind
(:mod:`tests.helpers.recording_cpu`) and skips elsewhere, naming why; without MKL (another architecture) too.
"""

from __future__ import annotations

import csv
import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest
import torch
import yaml

from tests.helpers.recording_cpu import RECORDING_KERNELS, WHY

ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "results" / "quick_preset" / "rows.csv"
TIMINGS = ("wall_s",)


def read(path: Path, seed: int, epochs: int) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        rows = [r for r in csv.DictReader(f) if int(r["seed"]) == seed and int(r["epoch"]) <= epochs]
    return sorted(
        ({k: v for k, v in r.items() if k not in TIMINGS} for r in rows), key=lambda r: (r["arm"], r["epoch"])
    )


@pytest.mark.skipif(
    platform.machine().lower() not in ("x86_64", "amd64") or not torch.backends.mkl.is_available(),
    reason="the committed rows were made with MKL's reproducible kernels on x86-64",
)
@pytest.mark.skipif(not RECORDING_KERNELS, reason=WHY)
def test_a_fresh_run_of_the_quick_preset_gives_the_committed_rows(tmp_path: Path) -> None:
    spec = yaml.safe_load((ROOT / "twodrl_bench" / "specs" / "quick_preset.yml").read_text())
    spec["protocol"]["epochs"], spec["seeds"] = 1, [0]
    (tmp_path / "spec.yml").write_text(yaml.safe_dump(spec))
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MKL_CBWR": "COMPATIBLE", "OMP_NUM_THREADS": "1"}
    command = [
        sys.executable,
        "-m",
        "twodrl_bench.cli",
        "run",
        str(tmp_path / "spec.yml"),
        "--out",
        str(tmp_path / "run"),
    ]
    out = subprocess.run(
        [*command, "--backend", "serial", "--no-report"], env=env, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr[-3000:]
    fresh = read(tmp_path / "run" / "rows.csv", seed=0, epochs=1)
    assert [r["arm"] for r in fresh] == ["a2c", "twoda2c"]
    assert fresh == read(COMMITTED, seed=0, epochs=1)
