"""The paper's experiments as a library (rl-zoo3 keeps its ``ExperimentManager`` in the package too).

- :mod:`.protocol`: presets, :class:`RunSpec`, hyperparameter files, CSV columns;
- :mod:`.algos`: algorithm names (``ALGOS``, the package's ``name -> class`` table);
- :mod:`.vec_env`: batched VecEnvs found through the Gymnasium registry's ``vector_entry_point``;
- :mod:`.trials`: an epoch's test trials in one batched call per step;
- :mod:`.runner`: one (algo, seed) run, epochs of exactly K learning trials, checkpoints, resume;
- :mod:`.grid`: backends (serial, processes, Ray), tidy CSV;
- :mod:`.reproduce`, :mod:`.transfer`, :mod:`.plots`: the command lines (``sb3-twodrl-*``).

Nothing here imports an env package: envs are named by ID, their packages by ``gym_packages``.
"""

from twodrl_bench.algos import ALGOS, algo_class
from twodrl_bench.grid import collect_results, run_grid
from twodrl_bench.protocol import COLUMNS, METRICS, PRESETS, RunSpec, load_hyperparams
from twodrl_bench.runner import run_pair
from twodrl_bench.trials import run_test_trials
from twodrl_bench.vec_env import VectorEnvAdapter, make_test_env, make_train_env

__all__ = [
    "ALGOS",
    "COLUMNS",
    "METRICS",
    "PRESETS",
    "RunSpec",
    "VectorEnvAdapter",
    "algo_class",
    "collect_results",
    "load_hyperparams",
    "make_test_env",
    "make_train_env",
    "run_grid",
    "run_pair",
    "run_test_trials",
]
