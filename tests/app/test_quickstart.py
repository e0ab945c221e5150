"""The Quick start learns: run from an empty folder, it prints a goal rate of at least 0.8 (20 deterministic tests).

The snippet is the README's first python block after its "Quick start" heading, run as written.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def quick_start() -> str:
    """The README's first python block after ``## Quick start``."""
    text = (ROOT / "README.md").read_text()
    return text[text.index("## Quick start") :].split("```python\n", 1)[1].split("```", 1)[0]


@pytest.mark.slow
def test_quick_start_reaches_the_goal_from_an_empty_folder(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run(
        [sys.executable, "-c", quick_start()], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr[-3000:]
    rates = re.findall(r"^goal rate: ([0-9.]+)$", out.stdout, flags=re.MULTILINE)
    assert len(rates) == 1 and float(rates[0]) >= 0.8, out.stdout[-2000:]
    assert (tmp_path / "twoda2c_nomad.zip").is_file()
