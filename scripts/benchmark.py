"""Benchmark on public tasks: :mod:`sb3_twodrl.experiments.benchmark` (``sb3-twodrl-benchmark``)."""

from sb3_twodrl.experiments.benchmark import main

if __name__ == "__main__":
    main()
