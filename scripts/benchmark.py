"""Benchmark on public tasks: :mod:`twodrl_bench.benchmark` (``sb3-twodrl-benchmark``)."""

from twodrl_bench.benchmark import main

if __name__ == "__main__":
    main()
