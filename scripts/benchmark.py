"""Benchmark on public tasks (issue 25): :mod:`sb3_twodrl.experiments.benchmark` (``sb3-twodrl-benchmark``)."""

from sb3_twodrl.experiments.benchmark import main

if __name__ == "__main__":
    main()
