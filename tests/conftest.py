"""Tests run tiny networks: one torch thread is fastest and keeps timings stable on 2 cores."""

import torch as th

th.set_num_threads(1)
