"""``results/offices/table.md`` is what ``scripts/bench_offices.py --table`` makes of the committed rows."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_offices_table_is_rebuilt_from_its_rows() -> None:
    folder = ROOT / "results" / "offices"
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "bench_offices.py"), "--table", str(folder / "rows.csv")],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    assert out.stdout == (folder / "table.md").read_text()
    assert "| L | twoda2c | 5/5 |" in out.stdout  # the rows hold every size
