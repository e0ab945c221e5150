#!/usr/bin/env python
"""Replay a trained agent with rl-zoo3's enjoy, TwoDimA2C included.

``python scripts/enjoy.py --algo twoda2c --env NomadOffice-v0 -f logs``: rl-zoo3's own options
(``--exp-id``, ``--load-best``, ``--stochastic``, ``--no-render``, ``-n``, ...).
``--record -o videos``: record a video instead (rl-zoo3's ``record_video``; the env must support
``render_mode="rgb_array"``). The log folder defaults to ``logs``, train.py's default.
"""

from __future__ import annotations

import importlib
import runpy
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from sb3_twodrl.zoo import _has_option, prepare_zoo_argv, run_zoo_entry


def _import_gym_packages(argv: list[str]) -> list[str]:
    if "--gym-packages" not in argv:
        return argv
    i = argv.index("--gym-packages")
    j = i + 1
    while j < len(argv) and not argv[j].startswith("-"):
        importlib.import_module(argv[j])
        j += 1
    return argv[:i] + argv[j:]


def main(argv: list[str] | None = None) -> None:
    argv = prepare_zoo_argv(sys.argv[1:] if argv is None else argv)
    if not _has_option(argv, "-f", "--folder"):
        argv += ["-f", "logs"]
    if "--record" in argv:
        argv.remove("--record")
        argv = _import_gym_packages(argv)  # record_video has no --gym-packages option
        run_zoo_entry("record_video.py", argv, lambda: runpy.run_module("rl_zoo3.record_video", run_name="__main__"))
        return
    from rl_zoo3.enjoy import enjoy

    run_zoo_entry("enjoy.py", argv, enjoy)


if __name__ == "__main__":
    main()
