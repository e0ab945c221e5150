"""Reports: what a study's rows say, by the rules its spec registered.

A study is one spec (``quick_preset``) or several parts (``paper_preset/NomadOffice-v0``, ...), each
run into its own folder (:mod:`twodrl_bench.runner`). :func:`report_study` reads the parts' resolved
specs and rows, copies them (with ``machine.json``) to the output folder (a single-part study's at its top, a part's in
``<out>/<part>/``) and calls the report the specs name (``twodrl_bench.reports.<report>``, or a module's
dotted path): ``report(parts, out) -> str``, or ``report(rows, specs, out) -> str`` with every part's rows
as ``csv.DictReader`` records and their specs. A report writes ``table.md`` and figures under ``out`` and
returns the text to print.
"""

from __future__ import annotations

import csv
import importlib
import inspect
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from twodrl_bench.folders import collect, read_spec
from twodrl_bench.spec import study_of


@dataclass
class Part:
    """One spec's run folder: ``name`` (the spec's), ``part`` ("" for a single-part study), its resolved
    ``spec`` and ``rows`` (a DataFrame)."""

    name: str
    part: str
    spec: dict[str, Any]
    rows: Any
    folder: Path


def find_parts(root: str | Path, study: str) -> list[Part]:
    """The parts of ``study`` under ``root``: ``root`` itself if its spec is the study's, else its sub-folders
    whose spec is a part of it (sorted by name).

    :raises ValueError: if there is none
    """
    root = Path(root)
    folders = [root] if (root / "spec.yml").is_file() else sorted(p for p in root.glob("*") if p.is_dir())
    parts = []
    for folder in folders:
        spec = read_spec(folder)
        if spec is None or study_of(spec["name"])[0] != study:
            continue
        parts.append(Part(spec["name"], study_of(spec["name"])[1], spec, collect(folder), folder))
    if not parts:
        raise ValueError(f"study {study!r}: no run folder of it under {root} (a spec.yml naming it)")
    return parts


def report_study(study: str, runs: str | Path = "runs", out: str | Path | None = None) -> str:
    """Report ``study`` from ``<runs>/<study>`` into ``out`` (default ``results/<study>``); the printed text.

    :raises ValueError: if the parts name different reports
    """
    return report_parts(find_parts(Path(runs) / study, study), Path(out) if out else Path("results") / study)


def report_run(folder: str | Path) -> str:
    """Report the study of the run folder ``folder`` (with its sibling parts) into the study's run folder."""
    folder = Path(folder)
    study, part = study_of(read_spec(folder)["name"])
    root = folder.parent if part else folder
    return report_parts(find_parts(root, study), root)


def report_parts(parts: list[Part], out: Path) -> str:
    """Copy each part's ``spec.yml``, ``rows.csv`` and ``machine.json`` under ``out``, run the parts' report,
    print its text.

    :raises ValueError: if a part's spec names no report, or the parts name different reports
    """
    unnamed = [p.name for p in parts if p.spec.get("report") is None]
    if unnamed:
        raise ValueError(
            f"the spec of {', '.join(unnamed)} names no report: add `report: <module>` to it "
            f"(twodrl_bench.reports.<module> or a dotted path), or read the rows in {parts[0].folder / 'rows.csv'}"
        )
    names = {p.spec["report"] for p in parts}
    if len(names) != 1:
        raise ValueError(f"the parts name different reports: {sorted(names)}")
    for p in parts:
        target = out / p.part if p.part else out
        target.mkdir(parents=True, exist_ok=True)
        if target.resolve() != p.folder.resolve():
            (target / "spec.yml").write_text(yaml.safe_dump(p.spec, sort_keys=False, width=120))
            for name in ("rows.csv", "machine.json"):
                if (p.folder / name).is_file():
                    shutil.copyfile(p.folder / name, target / name)
    name = names.pop()
    module = importlib.import_module(name if "." in name else f"twodrl_bench.reports.{name}")
    if next(iter(inspect.signature(module.report).parameters)) == "parts":
        text = module.report(parts, out)
    else:
        rows = []
        for p in parts:
            if (p.folder / "rows.csv").is_file():
                with (p.folder / "rows.csv").open(newline="") as f:
                    rows += list(csv.DictReader(f))
        text = module.report(rows, [p.spec for p in parts], out)
    print(text)
    return text
