"""Whether this CPU runs the kernels the committed rows were made with.

The committed rows (``results/quick_preset/rows.csv``, ``tests/data/timesteps_old_rows.json``) were made on an Intel
Xeon with AVX512-FP16 (``results/quick_preset/machine.json``) under ``MKL_CBWR=COMPATIBLE``. On an AMD EPYC without
AVX512-FP16 (seen 2026-12-05) A2C's rows were equal but TwoDimA2C's differed from the first epoch, also for the
code that made them: some kernel outside MKL (numpy's and torch's dispatch by instruction set) takes another path.
The tests that compare against those rows run where the CPU has the recording CPU's AVX512-FP16, and skip elsewhere.
"""

from __future__ import annotations

from pathlib import Path


def cpu_flags() -> set[str]:
    """The CPU's flags from ``/proc/cpuinfo`` (empty where it does not exist)."""
    path = Path("/proc/cpuinfo")
    if not path.exists():
        return set()
    for line in path.read_text().splitlines():
        if line.startswith(("flags", "Features")):
            return set(line.split(":", 1)[1].split())
    return set()


RECORDING_KERNELS = "avx512_fp16" in cpu_flags()
"""True where the CPU has the recording CPU's AVX512-FP16 (the rows are expected to be equal bit for bit)."""
WHY = "the committed rows were made on a CPU with AVX512-FP16 (tests/helpers/recording_cpu.py); this one lacks it"
