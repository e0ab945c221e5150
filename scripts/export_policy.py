#!/usr/bin/env python
"""``sb3-twodrl-export`` from a checkout: ``python scripts/export_policy.py model.zip policy.pt [--format onnx]``."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout without installing

from sb3_twodrl.export import main

if __name__ == "__main__":
    main()
