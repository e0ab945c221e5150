#!/usr/bin/env python
"""The paper's experiment from a checkout, without installing: ``sb3-twodrl-bench run`` (default spec quick_preset).

python scripts/reproduce.py                                     # quick_preset: 30 epochs, seeds 0-4
python scripts/reproduce.py paper_preset/NomadOffice-v0 --workers 4
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from twodrl_bench.cli import main

if __name__ == "__main__":
    args = sys.argv[1:]
    main(["run", *(args if args and not args[0].startswith("-") else ["quick_preset", *args])])
