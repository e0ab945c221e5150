"""What decides the bits of a run on a CPU: package versions, torch's threads and kernels, the CPU.

A study's run folder keeps it as ``machine.json`` (:func:`machine_info`): rows made on two machines that
differ here may differ bitwise, so that two folders' rows are compared knowing where they were made.

Measured (docs/studies.md, "Bits across machines"): on one x86-64 CPU, torch's MKL matrix products take a
code path per instruction set (AVX-512, AVX2, AVX/SSE4.2), each giving other rows from the first epoch on;
torch's own kernels (AVX-512 or AVX2) and 1 or 2 threads did not change a bit. MKL's conditional numerical
reproducibility (``MKL_CBWR=COMPATIBLE``) takes one path whatever the instruction set: the bench sets it
(:func:`use_reproducible_kernels`) at a cost of about 9% CPU time, unless the environment sets ``MKL_CBWR``.
"""

from __future__ import annotations

import os
import platform
import re
from importlib import metadata
from typing import Any

REPRODUCIBLE_KERNELS = {"MKL_CBWR": "COMPATIBLE"}
"""Environment that makes MKL take one code path whatever the instruction set (read by MKL at its first call);
measured on one CPU under AVX-512, AVX2 and SSE4.2, documented by Intel for other x86-64 CPUs."""
ENV_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "MKL_CBWR", "ATEN_CPU_CAPABILITY")
PACKAGES = ("torch", "stable-baselines3", "gymnasium", "numpy")


def use_reproducible_kernels() -> None:
    """Set :data:`REPRODUCIBLE_KERNELS` where the environment does not set them, before torch's first kernel
    (worker processes inherit it; Ray tasks get it through their runtime environment)."""
    for name, value in REPRODUCIBLE_KERNELS.items():
        os.environ.setdefault(name, value)


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def _cpu() -> dict[str, Any]:
    """Model and flags from ``/proc/cpuinfo`` (Linux), else what :mod:`platform` says."""
    try:
        text = open("/proc/cpuinfo").read()
    except OSError:
        return {"model": platform.processor() or platform.machine(), "flags": []}
    model = re.search(r"^model name\s*:\s*(.*)$", text, re.M)
    flags = re.search(r"^(?:flags|Features)\s*:\s*(.*)$", text, re.M)
    return {
        "model": model.group(1).strip() if model else platform.machine(),
        "flags": sorted(flags.group(1).split()) if flags else [],
        "count": os.cpu_count(),
    }


def _torch_build() -> dict[str, Any]:
    import torch as th

    config = th.__config__.show()
    mkl = re.search(r"Math Kernel Library Version ([^\s]+)", config)
    onednn = re.search(r"(?:MKL-DNN|oneDNN) v([^\s]+)", config)
    return {
        "threads": th.get_num_threads(),
        "interop_threads": th.get_num_interop_threads(),
        "cpu_capability": th.backends.cpu.get_cpu_capability(),
        "mkl": mkl.group(1) if mkl else None,
        "onednn": onednn.group(1) if onednn else None,
    }


def machine_info() -> dict[str, Any]:
    """Python, the packages of :data:`PACKAGES`, torch's build and threads, the CPU and :data:`ENV_VARS`."""
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "packages": {package: _version(package) for package in PACKAGES},
        "torch": _torch_build(),
        "cpu": _cpu(),
        "env": {name: os.environ.get(name) for name in ENV_VARS},
    }
