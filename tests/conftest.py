"""Tests run tiny networks: one torch thread is fastest and keeps timings stable on 2 cores.

MKL's reproducible kernels are set before any test runs a torch kernel, as the bench sets them for its runs: the
fixtures that hold rows of the bench were made with them.
"""

from twodrl_bench.machine import use_reproducible_kernels

use_reproducible_kernels()

import torch as th  # noqa: E402

th.set_num_threads(1)
