"""The installed zoo commands: ``sb3-twodrl-train`` and ``sb3-twodrl-enjoy`` (rl-zoo3's ``train`` and ``enjoy``).

Both register ``twoda2c`` and ``twodppo`` (:func:`sb3_twodrl.zoo.register_zoo`) and import the installed env packages
that list themselves under the ``sb3_twodrl.gym_packages`` entry points (:func:`sb3_twodrl.zoo.import_gym_packages`),
so their env IDs work from any folder without ``--gym-packages``; every rl-zoo3 option is kept, and
``--num-threads`` defaults to 1 (rl-zoo3's default keeps torch's thread count: several times slower for these small
networks on a shared machine, docs/zoo.md).
``sb3-twodrl-train`` reads the packaged ``<algo>.yml`` (:mod:`sb3_twodrl.hyperparams`) for a2c, ppo, twoda2c and
twodppo unless ``-conf/--conf-file`` names another file. A command whose extra is missing exits, before any work,
with the ``pip install`` line that adds it (:func:`require_extra`).
"""

from __future__ import annotations

import importlib
import runpy
import sys

__all__ = ["ZOO_MODULES", "enjoy", "require_extra", "train"]

ZOO_MODULES = ("rl_zoo3", "optuna", "pandas", "requests")
"""What the ``zoo`` extra installs and the commands import (rl-zoo3's enjoy imports ``requests`` undeclared)."""


def require_extra(extra: str, *modules: str) -> None:
    """Exit (status 1) naming ``pip install "sb3-twodrl[<extra>]"`` if one of ``modules`` cannot be imported."""
    missing = []
    for module in modules:
        try:
            importlib.import_module(module)
        except ImportError:
            missing.append(module)
    if missing:
        sys.exit(
            f"{', '.join(missing)} not installed: this command needs the '{extra}' extra, "
            f'pip install "sb3-twodrl[{extra}]"'
        )


def train(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-train``: rl-zoo3's ``train`` with the 2D-RL algorithms and the packaged hyperparameters."""
    require_extra("zoo", *ZOO_MODULES)
    from rl_zoo3.train import train as zoo_train

    from sb3_twodrl.zoo import _has_option, prepare_zoo_argv, run_zoo_entry

    argv = prepare_zoo_argv(sys.argv[1:] if argv is None else argv, packaged_conf=True)
    if not _has_option(argv, "--num-threads"):
        argv += ["--num-threads", "1"]
    run_zoo_entry("sb3-twodrl-train", argv, zoo_train)


def enjoy(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-enjoy``: rl-zoo3's ``enjoy`` (``-f`` defaults to ``logs``, train's folder).

    ``--record -o videos`` records a video instead (rl-zoo3's ``record_video``, needs ``moviepy``; the env must
    support ``render_mode="rgb_array"``).
    """
    require_extra("zoo", *ZOO_MODULES)
    from sb3_twodrl.zoo import _has_option, prepare_zoo_argv, run_zoo_entry

    argv = prepare_zoo_argv(sys.argv[1:] if argv is None else argv)
    if not _has_option(argv, "-f", "--folder"):
        argv += ["-f", "logs"]
    if "--record" in argv:
        try:
            importlib.import_module("moviepy")
        except ImportError:
            sys.exit("moviepy not installed: --record needs it, pip install moviepy")
        argv.remove("--record")
        argv = _import_gym_packages(argv)  # record_video has no --gym-packages option
        run_zoo_entry("sb3-twodrl-enjoy", argv, lambda: runpy.run_module("rl_zoo3.record_video", run_name="__main__"))
        return
    from rl_zoo3.enjoy import enjoy as zoo_enjoy

    if not _has_option(argv, "--num-threads"):
        argv += ["--num-threads", "1"]
    run_zoo_entry("sb3-twodrl-enjoy", argv, zoo_enjoy)


def _import_gym_packages(argv: list[str]) -> list[str]:
    """Import the modules after ``--gym-packages`` and drop the option (for rl-zoo3's ``record_video``)."""
    if "--gym-packages" not in argv:
        return argv
    i = argv.index("--gym-packages")
    j = i + 1
    while j < len(argv) and not argv[j].startswith("-"):
        importlib.import_module(argv[j])
        j += 1
    return argv[:i] + argv[j:]
