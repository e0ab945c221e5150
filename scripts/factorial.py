#!/usr/bin/env python
"""The factorial's tables from its cells' rows (docs/factorial.md): see :mod:`twodrl_bench.factorial`.

python scripts/factorial.py --runs results/factorial --out results/factorial
"""

from twodrl_bench.factorial import main

if __name__ == "__main__":
    main()
