"""rl-zoo3 integration: register TwoDimA2C as ``twoda2c`` and TwoDimPPO as ``twodppo``, with Optuna samplers.

>>> from twodrl_zoo.zoo import register_zoo
>>> register_zoo()  # then rl_zoo3.train.train() / rl_zoo3.enjoy.enjoy() accept --algo twoda2c / twodppo

rl-zoo3 looks algorithms up in ``rl_zoo3.utils.ALGOS`` and samplers in
``rl_zoo3.hyperparams_opt.HYPERPARAMS_SAMPLER`` / ``HYPERPARAMS_CONVERTER`` (the converter turns a
stored Optuna trial back into constructor arguments, for ``--trial-id``). Those are module-level
dicts that the training and enjoy scripts import by reference, so registering means adding keys to
them, before rl-zoo3 parses its command line (its ``--algo`` choices are taken from ``ALGOS``).

Requires the ``zoo`` extra. The installed commands ``sb3-twodrl-train`` and ``sb3-twodrl-enjoy``
(:mod:`twodrl_zoo.cli`) call :func:`register_zoo`.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib.metadata import entry_points
from typing import Any

from sb3_twodrl import ALGOS
from twodrl_zoo.hyperparams import PACKAGED, hyperparams_path

__all__ = [
    "GYM_PACKAGES_GROUP",
    "ZOO_ALGOS",
    "convert_two_dim_params",
    "import_gym_packages",
    "prepare_zoo_argv",
    "register_zoo",
    "run_zoo_entry",
    "sample_two_dim_params",
    "sample_twoda2c_params",
    "sample_twodppo_params",
]


def convert_two_dim_params(sampled_params: dict[str, Any]) -> dict[str, Any]:
    """Turn sampled (or stored) trial parameters into TwoDimA2C or TwoDimPPO constructor arguments."""
    from rl_zoo3.hyperparams_opt import convert_onpolicy_params

    params = dict(sampled_params)
    if "one_minus_punishment_gae_lambda" in params:
        params["punishment_gae_lambda"] = 1.0 - params.pop("one_minus_punishment_gae_lambda")
    return convert_onpolicy_params(params)


def sample_two_dim_params(trial: Any) -> dict[str, Any]:
    """The 2D-RL part of the search spaces (raw trial parameters, for :func:`convert_two_dim_params`).

    - ``punishment_gamma`` in [0, 0.99]: the paper's point is that punishment is short-sighted (0.1);
    - ``one_minus_punishment_gae_lambda`` in [1e-4, 1] (log): punishment GAE lambda in [0, 0.9999];
    - ``punishment_vf_coef`` in [0.1, 1] and ``punishment_weight`` in [0.25, 4] (log);
    - ``min_temperature`` in [0.1, 10] (log): the interest floor.
    """
    return {
        "punishment_gamma": trial.suggest_float("punishment_gamma", 0.0, 0.99),
        "one_minus_punishment_gae_lambda": trial.suggest_float(
            "one_minus_punishment_gae_lambda", 0.0001, 1.0, log=True
        ),
        "punishment_vf_coef": trial.suggest_float("punishment_vf_coef", 0.1, 1.0),
        "punishment_weight": trial.suggest_float("punishment_weight", 0.25, 4.0, log=True),
        "min_temperature": trial.suggest_float("min_temperature", 0.1, 10.0, log=True),
    }


def sample_twoda2c_params(trial: Any, n_actions: int, n_envs: int, additional_args: dict) -> dict[str, Any]:
    """Optuna search space of TwoDimA2C: A2C's space plus the 2D-RL hyperparameters.

    The A2C part (``n_steps``, ``gamma``, ``gae_lambda``, ``learning_rate``, ``max_grad_norm``,
    ``ent_coef``, network) is the same as rl-zoo3's A2C sampler, so the two algorithms are tuned on
    equal terms; added: the 2D-RL space of :func:`sample_two_dim_params`.
    """
    n_steps = trial.suggest_categorical("n_steps", [5, 8, 16, 32, 64, 128, 256, 512])
    one_minus_gamma = trial.suggest_float("one_minus_gamma", 0.0001, 0.2, log=True)
    one_minus_gae_lambda = trial.suggest_float("one_minus_gae_lambda", 0.0001, 0.1, log=True)
    learning_rate = trial.suggest_float("learning_rate", 1e-5, 0.003, log=True)
    max_grad_norm = trial.suggest_float("max_grad_norm", 0.3, 2)
    ent_coef = trial.suggest_float("ent_coef", 1e-8, 0.1, log=True)
    net_arch = trial.suggest_categorical("net_arch", ["small", "medium"])
    activation_fn = trial.suggest_categorical("activation_fn", ["tanh", "relu"])

    trial.set_user_attr("gamma", 1 - one_minus_gamma)
    sampled: dict[str, Any] = {
        "n_steps": n_steps,
        "one_minus_gamma": one_minus_gamma,
        "one_minus_gae_lambda": one_minus_gae_lambda,
        "learning_rate": learning_rate,
        "ent_coef": ent_coef,
        "max_grad_norm": max_grad_norm,
        "net_arch": net_arch,
        "activation_fn": activation_fn,
    }
    return convert_two_dim_params({**sampled, **sample_two_dim_params(trial)})


def sample_twodppo_params(trial: Any, n_actions: int, n_envs: int, additional_args: dict) -> dict[str, Any]:
    """Optuna search space of TwoDimPPO: rl-zoo3's PPO space (its own sampler) plus :func:`sample_two_dim_params`."""
    from rl_zoo3.hyperparams_opt import sample_ppo_params

    params = sample_ppo_params(trial, n_actions, n_envs, additional_args)
    two_dim = sample_two_dim_params(trial)
    two_dim["punishment_gae_lambda"] = 1.0 - two_dim.pop("one_minus_punishment_gae_lambda")
    return {**params, **two_dim}


ZOO_SAMPLERS: dict[str, Callable[..., dict[str, Any]]] = {
    "twoda2c": sample_twoda2c_params,
    "twodppo": sample_twodppo_params,
}
"""The Optuna search space of each 2D-RL algorithm, by its name in :data:`sb3_twodrl.ALGOS`."""
ZOO_ALGOS: dict[str, type] = {name: ALGOS[name] for name in ZOO_SAMPLERS}
"""The 2D-RL algorithms by their rl-zoo3 names: the library's table (:data:`sb3_twodrl.ALGOS`), whose stock
entries (``a2c``, ``ppo``) rl-zoo3 has already."""


def register_zoo(algos: Mapping[str, type] | None = None) -> None:
    """Register ``twoda2c`` and ``twodppo`` in rl-zoo3's algorithm, sampler and converter tables (idempotent); with
    ``algos``, every name of that table too (the bench's :data:`twodrl_bench.algorithms.ALGOS`, so that rl-zoo3's
    ``ExperimentManager`` builds its classes). The one place that writes rl-zoo3's tables.

    :raises ValueError: naming the algorithm, if ``algos`` gives a name rl-zoo3 has for another class
    """
    from rl_zoo3 import hyperparams_opt, utils

    clash = [name for name, algo in (algos or {}).items() if utils.ALGOS.get(name, algo) is not algo]
    if clash:
        raise ValueError(f"algos: {', '.join(clash)} name other classes in rl-zoo3's table")
    utils.ALGOS.update(algos or {})
    for key, algo in ZOO_ALGOS.items():
        utils.ALGOS[key] = algo
        hyperparams_opt.HYPERPARAMS_SAMPLER[key] = ZOO_SAMPLERS[key]
        hyperparams_opt.HYPERPARAMS_CONVERTER[key] = convert_two_dim_params


def has_option(argv: list[str], *names: str) -> bool:
    """Whether ``argv`` gives any of the flags ``names`` (``--flag value`` or ``--flag=value``)."""
    return any(a in names or any(a.startswith(n + "=") for n in names) for a in argv)


def option_value(argv: list[str], *names: str) -> str | None:
    """The value ``argv`` gives the first of the flags ``names`` it has, None where it gives none."""
    for i, a in enumerate(argv):
        for n in names:
            if a == n and i + 1 < len(argv):
                return argv[i + 1]
            if a.startswith(n + "="):
                return a.split("=", 1)[1]
    return None


GYM_PACKAGES_GROUP = "sb3_twodrl.gym_packages"
"""Entry-point group of the packages that register Gymnasium env IDs on import. An env package lists itself in
its ``pyproject.toml`` (``[project.entry-points."sb3_twodrl.gym_packages"]``, ``name = "module"``); the commands
import every one, so its IDs need no ``--gym-packages``."""


def import_gym_packages() -> None:
    """Import the module of every entry point in :data:`GYM_PACKAGES_GROUP` (which registers its env IDs)."""
    for entry_point in entry_points(group=GYM_PACKAGES_GROUP):
        entry_point.load()


def prepare_zoo_argv(argv: list[str], packaged_conf: bool = False) -> list[str]:
    """Make rl-zoo3's command line ready for this project (used by :mod:`twodrl_zoo.cli`).

    Registers ``twoda2c`` and ``twodppo`` (:func:`register_zoo`), imports the env packages of the
    :data:`GYM_PACKAGES_GROUP` entry points (:func:`import_gym_packages`; ``--gym-packages`` adds others), and, when
    ``packaged_conf`` and no ``-conf/--conf-file`` is given, adds ``--conf-file`` with the packaged ``<algo>.yml``
    (:func:`~twodrl_zoo.hyperparams.hyperparams_path`) of the algos in :data:`~twodrl_zoo.hyperparams.PACKAGED`;
    the other algos keep rl-zoo3's own files.
    """
    register_zoo()
    import_gym_packages()
    argv = list(argv)
    algo = option_value(argv, "--algo") or "ppo"
    if packaged_conf and algo in PACKAGED and not has_option(argv, "-conf", "--conf-file"):
        argv += ["--conf-file", str(hyperparams_path(algo))]
    return argv


def run_zoo_entry(prog: str, argv: list[str], entry: Callable[[], Any]) -> None:
    """Call an rl-zoo3 entry point (which parses ``sys.argv``) with ``argv``."""
    old = sys.argv
    sys.argv = [prog, *argv]
    try:
        entry()
    finally:
        sys.argv = old


_DICT_OPTIONS = ("--env-kwargs", "--eval-env-kwargs", "--hyperparams")


def dict_options(argv: list[str]) -> tuple[list[str], dict[str, dict[str, Any]]]:
    """``argv`` without its rl-zoo3 ``key:value`` options, and those options parsed as rl-zoo3 parses them."""
    import argparse

    from rl_zoo3.utils import StoreDict

    parser = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    for option in _DICT_OPTIONS:
        parser.add_argument(option, type=str, nargs="+", action=StoreDict, default={})
    known, rest = parser.parse_known_args(argv)
    return rest, {option: getattr(known, option[2:].replace("-", "_")) for option in _DICT_OPTIONS}
