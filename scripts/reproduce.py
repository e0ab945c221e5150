#!/usr/bin/env python
"""The paper's experiment: TwoDimA2C vs A2C (``--help``); logic in :mod:`twodrl_bench`.

python scripts/reproduce.py --env NomadOfficeMemorable-v0 --preset quick
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from twodrl_bench.reproduce import main

if __name__ == "__main__":
    main()
