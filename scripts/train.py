#!/usr/bin/env python
"""``sb3-twodrl-train`` from a checkout: ``python scripts/train.py --algo twoda2c --env NomadOffice-v0``.

rl-zoo3's train with TwoDimA2C and TwoDimPPO registered and the packaged hyperparameters (:mod:`twodrl_zoo.cli`).
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "envs"))  # the env package, envs/twodrl_envs/

from twodrl_zoo.cli import train

if __name__ == "__main__":
    train()
