#!/usr/bin/env python
"""Redraw figures 3-5 and the results table from a results CSV: ``python scripts/plots.py results.csv``."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from twodrl_bench.plots import main

if __name__ == "__main__":
    main()
