#!/usr/bin/env python
"""The factorial's tables from its cells' rows (docs/factorial.md): see :mod:`sb3_twodrl.experiments.factorial`.

python scripts/factorial.py --runs results/factorial --out results/factorial
"""

from sb3_twodrl.experiments.factorial import main

if __name__ == "__main__":
    main()
