#!/usr/bin/env python
"""Paper section 3.5: transfer of database training to the "real" robot (``--help``); see twodrl_bench.

python scripts/transfer.py --quick          # < 10 min on 2 cores
python scripts/transfer.py                  # 5 seeds, 100 trials, 300k steps
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from twodrl_bench.transfer import main

if __name__ == "__main__":
    main()
