#!/usr/bin/env python
"""Train with rl-zoo3, TwoDimA2C included: ``python scripts/train.py --algo twoda2c --env NomadOffice-v0``.

Every rl-zoo3 option works (``--tensorboard-log``, ``--eval-freq``, ``--save-freq``, ``-optimize``,
``--storage``/``--study-name`` for an Optuna study shared by several machines, ``-params``, ...;
see ``--help``). Hyperparameters default to the packaged ``<algo>.yml`` (:mod:`sb3_twodrl.hyperparams`)
for a2c, ppo, twoda2c and twodppo, to rl-zoo3's own for other algos; ``--conf-file`` picks another file.
The Nomad office envs are imported automatically when installed.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from sb3_twodrl.zoo import prepare_zoo_argv, run_zoo_entry


def main(argv: list[str] | None = None) -> None:
    argv = prepare_zoo_argv(sys.argv[1:] if argv is None else argv, packaged_conf=True)
    from rl_zoo3.train import train

    run_zoo_entry("train.py", argv, train)


if __name__ == "__main__":
    main()
