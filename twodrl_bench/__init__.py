"""The research bench: the paper's studies as data (specs), one runner, reports.

- :mod:`.spec`: load, validate and compare specs (``specs/<study>.yml``, ``specs/<study>/<part>.yml``);
- :mod:`.experiment`: the study object, a spec resolved once (:class:`Experiment`), and its jobs (:class:`Job`);
  :mod:`.settings`: an arm's settings file, entry and defaults in force;
- :mod:`.runner`: every (arm, seed) job of an experiment into a run folder, resumed and guarded; :mod:`.backends`:
  local processes or Ray tasks; :mod:`.machine`: what decides the bits;
- the jobs, each ``run(job) -> rows``: :mod:`.epochs` (epochs of exactly K learning trials and M test trials) and
  :mod:`.timesteps` (rl-zoo3's training, a final evaluation), resumable by one scheme (:mod:`.jobs`);
- :mod:`.reports`: what a study's rows say (tables, figures);
- :mod:`.cli`: ``sb3-twodrl-bench run | report | status``;
- :mod:`.algorithms`: the bench's algorithms (stock arms on the fast path, variants, self-tuning entropy) by name;
- shared machinery: :mod:`.protocol` (CSV columns, trial seeds), :mod:`.trials` (an epoch's test trials),
  :mod:`.checkpoint`, :mod:`.intervals`, :mod:`.plots`; the batched VecEnvs are the app's
  (:mod:`twodrl_zoo.vec_env`).

Nothing here imports an env package: envs are named by ID, their packages by ``gym_packages``, and the route labels
whose shares are columns by value (:data:`.protocol.ROUTES`).
"""

from twodrl_bench.machine import use_reproducible_kernels

use_reproducible_kernels()  # before any module below runs a torch kernel

from twodrl_bench.algorithms import ALGOS, algo_class  # noqa: E402
from twodrl_bench.experiment import Experiment, Job  # noqa: E402
from twodrl_bench.protocol import COLUMNS, METRICS  # noqa: E402
from twodrl_bench.runner import run_job, run_study  # noqa: E402
from twodrl_bench.spec import load_spec  # noqa: E402
from twodrl_bench.trials import run_test_trials  # noqa: E402
from twodrl_zoo.vec_env import VectorEnvAdapter, make_test_env, make_train_env  # noqa: E402

__all__ = [
    "ALGOS",
    "COLUMNS",
    "METRICS",
    "Experiment",
    "Job",
    "VectorEnvAdapter",
    "algo_class",
    "load_spec",
    "make_test_env",
    "make_train_env",
    "run_job",
    "run_study",
    "run_test_trials",
]
