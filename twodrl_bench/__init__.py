"""The research bench: the paper's studies as data (specs), one runner, reports.

- :mod:`.spec`: load, validate, resolve and compare specs (``specs/<study>.yml``, ``specs/<study>/<part>.yml``);
- :mod:`.runner`: every (arm, seed) job of a spec into a run folder, resumed and guarded; :mod:`.backends`:
  local processes or Ray tasks; :mod:`.machine`: what decides the bits;
- :mod:`.epochs`: the epoch job (epochs of exactly K learning trials and M test trials, checkpoints, resume);
- :mod:`.reports`: what a study's rows say (tables, figures);
- :mod:`.cli`: ``sb3-twodrl-bench run | report | status``;
- shared machinery: :mod:`.protocol` (run specs, CSV columns), :mod:`.algos` (algorithm names),
  :mod:`.vec_env` (batched VecEnvs), :mod:`.trials` (an epoch's test trials), :mod:`.checkpoint`,
  :mod:`.intervals`, :mod:`.plots`.

Nothing here imports an env package: envs are named by ID, their packages by ``gym_packages``.
"""

from twodrl_bench.machine import use_reproducible_kernels

use_reproducible_kernels()  # before any module below runs a torch kernel

from twodrl_bench.algos import ALGOS, algo_class  # noqa: E402
from twodrl_bench.epochs import run_pair  # noqa: E402
from twodrl_bench.protocol import COLUMNS, METRICS, PRESETS, RunSpec, load_hyperparams  # noqa: E402
from twodrl_bench.runner import run_study  # noqa: E402
from twodrl_bench.spec import load_spec, resolve  # noqa: E402
from twodrl_bench.trials import run_test_trials  # noqa: E402
from twodrl_bench.vec_env import VectorEnvAdapter, make_test_env, make_train_env  # noqa: E402

__all__ = [
    "ALGOS",
    "COLUMNS",
    "METRICS",
    "PRESETS",
    "RunSpec",
    "VectorEnvAdapter",
    "algo_class",
    "load_hyperparams",
    "load_spec",
    "make_test_env",
    "make_train_env",
    "resolve",
    "run_pair",
    "run_study",
    "run_test_trials",
]
