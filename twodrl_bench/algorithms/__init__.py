"""The bench's algorithms, plain subclasses of the library's and SB3's, and the one table of the names specs give them
(:data:`ALGOS`): the package's table :data:`sb3_twodrl.ALGOS`, the stock algorithms on the fast path
(:mod:`.baselines`, SB3's numbers bit for bit), the ablation's variants (:mod:`.variants`) and the self-tuning entropy
arms (:mod:`.auto_entropy`). A bench class is named ``<algo><suffix>`` after the algorithm it changes
(:data:`SUFFIXES`); every other name the bench uses is a view of the table (:data:`FAST_PATH`, :func:`stock_algo`).

A name means one class everywhere: ``a2c`` is SB3's ``A2C`` here, in the library, in rl-zoo3 and in both protocols'
rows. The epoch protocol trains a stock arm on the fast path (:func:`fast_path`), the same numbers in less time
(``tests/bench/test_fast.py``), under the arm's own ``algo`` label. Every model of the bench and of the scripts that
is not rl-zoo3's (:mod:`twodrl_bench.timesteps` builds with ``sb3-twodrl-train``'s manager, from this table
registered by :func:`twodrl_zoo.zoo.register_zoo`) is made by :func:`make_model`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_twodrl import ALGOS as PACKAGE_ALGOS
from twodrl_bench.algorithms.auto_entropy import (
    AutoEntropyA2C,
    AutoEntropyPPO,
    AutoEntropyTwoDimA2C,
    AutoEntropyTwoDimPPO,
)
from twodrl_bench.algorithms.baselines import FastA2C, FastPPO
from twodrl_bench.algorithms.variants import VariantTwoDimA2C, VariantTwoDimPPO

ALGOS: dict[str, type[BaseAlgorithm]] = {
    **PACKAGE_ALGOS,  # a2c and ppo (SB3's own classes), twoda2c and twodppo
    "a2c_fast": FastA2C,
    "ppo_fast": FastPPO,
    "twoda2c_variant": VariantTwoDimA2C,
    "twodppo_variant": VariantTwoDimPPO,
    "a2c_auto": AutoEntropyA2C,
    "ppo_auto": AutoEntropyPPO,
    "twoda2c_auto": AutoEntropyTwoDimA2C,
    "twodppo_auto": AutoEntropyTwoDimPPO,
}
"""Every algorithm the experiment commands and the scripts can run, by name: the one table of the bench."""
SUFFIXES = ("_fast", "_variant", "_auto")
"""A bench class named ``<algo><suffix>`` is ``<algo>`` changed: ``_fast`` the same numbers on the fast path,
``_variant`` the ablation's options, ``_auto`` a learned entropy coefficient (it reads ``<algo>``'s settings)."""
FAST_PATH: dict[str, str] = {name.removesuffix("_fast"): name for name in ALGOS if name.endswith("_fast")}
"""The name of the class the epoch protocol trains for a stock ``algo`` (SB3's numbers bit for bit, faster): a view
of :data:`ALGOS`, ``<algo>_fast`` for ``<algo>``."""


def algo_class(name: str) -> type[BaseAlgorithm]:
    """The class registered as ``name`` in :data:`ALGOS`.

    :raises ValueError: naming ``name`` and the table's names, if it has none such
    """
    if name not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {name!r}")
    return ALGOS[name]


def fast_path(name: str) -> str:
    """The name of the class the epoch protocol trains for a spec's ``algo`` ``name``: its :data:`FAST_PATH` one if
    any, else ``name``."""
    algo_class(name)
    return FAST_PATH.get(name, name)


def stock_algo(name: str) -> str:
    """The stock algorithm (SB3's own class in :data:`ALGOS`: ``a2c``, ``ppo``) that the class of ``name`` extends,
    e.g. ``a2c`` for ``twoda2c`` and ``twoda2c_auto``: whose entry an arm reads from rl-zoo3's own files.

    :raises ValueError: if ``name`` is not in :data:`ALGOS`
    """
    cls = algo_class(name)
    return next(
        stock
        for stock, base in ALGOS.items()
        if base.__module__.startswith("stable_baselines3.") and issubclass(cls, base)
    )


def make_model(name: str, env: Any, settings: Mapping[str, Any] | None = None, **options: Any) -> BaseAlgorithm:
    """A new model of the algorithm ``name`` (:func:`algo_class`) on ``env`` (a VecEnv or an env id): ``settings``
    are its constructor arguments as an entry gives them ready (the policy under ``policy``, default ``MlpPolicy``),
    ``options`` the run's own (``seed``, ``device``, ``tensorboard_log``).

    :raises ValueError: if ``name`` is not in :data:`ALGOS`
    """
    arguments = dict(settings or {})
    policy = arguments.pop("policy", "MlpPolicy")
    return algo_class(name)(policy, env, **arguments, **options)
