"""``sb3-twodrl-bench``: run a study's spec, report a study, show the state of run folders.

    sb3-twodrl-bench run SPEC [--out DIR] [--backend process|ray|serial] [--address ADDR] [--workers N] [--arms A ..]
    sb3-twodrl-bench report STUDY [--runs DIR] [--out DIR]
    sb3-twodrl-bench status [DIR]

SPEC is a packaged spec's name (``quick_preset``, ``paper_preset/NomadOffice-v0``; ``list`` prints them) or a
path to a ``.yml``. ``run`` writes into ``runs/<spec name>`` (or ``--out``), resumes what a folder holds,
refuses a folder of another spec, and ends with the study's report. See ``docs/studies.md``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from twodrl_bench.backends import BACKENDS


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="sb3-twodrl-bench", description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter
    )
    sub = p.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run (or resume) every (arm, seed) job of a spec, then its study's report")
    run.add_argument("spec", help="a packaged spec's name or a path to a .yml")
    run.add_argument("--out", type=Path, help="the run folder (default: runs/<spec name>)")
    run.add_argument("--backend", choices=BACKENDS, default="process", help="where jobs run (default: %(default)s)")
    run.add_argument("--address", help="a Ray cluster to join (HOST:PORT or 'auto'; default: a local Ray instance)")
    run.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="jobs at a time (default: CPU count)")
    run.add_argument("--arms", nargs="+", help="run only these arms of the spec (default: every arm)")
    run.add_argument("--no-report", action="store_true", help="do not run the report at the end")
    report = sub.add_parser("report", help="the report of a study from its run folders")
    report.add_argument("study", help="a study's name (quick_preset, paper_preset, factorial, ...)")
    report.add_argument("--runs", type=Path, default=Path("runs"), help="where its run folders are (default: runs)")
    report.add_argument("--out", type=Path, help="the report's folder (default: results/<study>)")
    status = sub.add_parser("status", help="finished, running and pending jobs of the run folders under DIR")
    status.add_argument("dir", nargs="?", type=Path, default=Path("runs"), help="default: runs")
    sub.add_parser("list", help="the packaged specs")
    args = p.parse_args(argv)
    if args.command == "run" and args.address and args.backend != "ray":
        p.error(f"--address joins a Ray cluster: it needs --backend ray, got --backend {args.backend}")
    return args


def status(root: Path) -> str:
    """One line per run folder under ``root`` (its spec.yml): jobs finished, running (epochs or timesteps done) and
    pending."""
    from twodrl_bench.folders import read_spec, rows_path
    from twodrl_bench.jobs import progress_path

    lines = []
    for path in sorted(root.rglob("spec.yml")):
        folder = path.parent
        spec = read_spec(folder)
        jobs = [(arm, seed) for arm in spec["arms"] for seed in spec["seeds"]]
        done = [job for job in jobs if rows_path(folder, *job).exists()]
        running = []
        for arm, seed in jobs:
            progress = progress_path(folder, f"{arm}_seed{seed}")
            if (arm, seed) not in done and progress.exists():
                last = (progress.read_text().split() or ["0"])[-1]
                length = spec["protocol"].get("epochs") or spec["protocol"].get("timesteps") or "?"
                running.append(f"{arm}_seed{seed} {last}/{length}")
        line = f"{spec['name']} ({folder}): {len(done)}/{len(jobs)} jobs done"
        if running:
            line += "; started: " + ", ".join(running)
        lines.append(line)
    return "\n".join(lines) if lines else f"no run folder (spec.yml) under {root}"


BENCH_MODULES = ("pandas", "scipy", "matplotlib")
"""What the ``bench`` extra installs and every study's rows, intervals and figures need."""


def main(argv: list[str] | None = None) -> None:
    from twodrl_zoo.cli import require_extra

    args = parse_args(argv)
    require_extra("bench", *BENCH_MODULES)
    if args.command == "run":
        from twodrl_bench.runner import run_study

        run_study(args.spec, args.out, args.backend, args.workers, args.address, not args.no_report, args.arms)
    elif args.command == "report":
        from twodrl_bench.reports import report_study

        report_study(args.study, args.runs, args.out)
    elif args.command == "status":
        print(status(args.dir))
    else:
        from twodrl_bench.spec import packaged_specs

        print("\n".join(packaged_specs()))


if __name__ == "__main__":
    main()
