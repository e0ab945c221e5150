#!/usr/bin/env python
"""``sb3-twodrl-enjoy`` from a checkout: ``python scripts/enjoy.py --algo twoda2c --env NomadOffice-v0``.

rl-zoo3's enjoy with TwoDimA2C and TwoDimPPO registered; ``--record -o videos`` records a video
(:mod:`twodrl_zoo.cli`).
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "envs"))  # the env package, envs/twodrl_envs/

from twodrl_zoo.cli import enjoy

if __name__ == "__main__":
    enjoy()
