"""A run folder's files (default ``runs/<spec name>``): ``spec.yml`` (the resolved spec), ``machine.json``
(:func:`record_machine`: the machines its jobs ran on), ``rows/<arm>_seed<seed>.csv`` per finished job (written
atomically: a job with a file is done) and ``rows.csv`` (:func:`collect`: every job's rows). The runner
(:mod:`twodrl_bench.runner`) writes them; the reports (:mod:`twodrl_bench.reports`) read them.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import yaml

from twodrl_bench.checkpoint import atomic_write_bytes
from twodrl_bench.spec import Spec

Row = dict[str, Any]


def rows_path(folder: str | Path, arm: str, seed: int) -> Path:
    return Path(folder) / "rows" / f"{arm}_seed{seed}.csv"


def write_rows(path: Path, rows: list[Row]) -> None:
    """Write ``rows`` as CSV atomically (temporary file, then rename); the columns in first-seen order."""
    columns = list(dict.fromkeys(key for row in rows for key in row))
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=columns)
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_bytes(path, buf.getvalue().encode())


def append_row(path: Path, fields: tuple[str, ...], row: Row) -> None:
    """Append ``row`` (its ``fields``) to the CSV ``path``, with the header where the file is new (scripts' rows)."""
    new = not path.exists()
    with path.open("a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        if new:
            writer.writeheader()
        writer.writerow(row)


def read_spec(folder: str | Path) -> Spec | None:
    """The resolved spec stored in ``folder`` (None if there is none)."""
    path = Path(folder) / "spec.yml"
    return yaml.safe_load(path.read_text()) if path.is_file() else None


def collect(folder: str | Path):
    """Every rows file of ``folder`` as one DataFrame, sorted by arm, seed (and epoch), written to ``rows.csv``; a
    folder without rows files (a study's copy under ``results/``) gives its ``rows.csv`` as it is."""
    import pandas as pd

    files = sorted((Path(folder) / "rows").glob("*.csv"))
    if not files:
        collected = Path(folder) / "rows.csv"
        return pd.read_csv(collected) if collected.is_file() else pd.DataFrame()
    df = pd.concat([pd.read_csv(f) for f in files], ignore_index=True)
    keys = [k for k in ("arm", "seed", "epoch") if k in df.columns]
    df = df.sort_values(keys, kind="stable").reset_index(drop=True)
    buf = io.StringIO()
    df.to_csv(buf, index=False)
    atomic_write_bytes(Path(folder) / "rows.csv", buf.getvalue().encode())
    return df


def record_machine(folder: str | Path, info: dict[str, Any]) -> list[dict[str, Any]]:
    """Add ``info`` (:func:`~twodrl_bench.machine.machine_info` of a job's process) to ``machine.json``, the list
    of the distinct machines whose jobs ran into ``folder``, in order of first use (their rows may differ bitwise)."""
    path = Path(folder) / "machine.json"
    machines = json.loads(path.read_text()) if path.is_file() else []
    if info not in machines:
        if machines:
            print(f"{folder}: jobs ran on another machine than before (machine.json lists each)")
        machines.append(info)
        atomic_write_bytes(path, json.dumps(machines, indent=1).encode())
    return machines
