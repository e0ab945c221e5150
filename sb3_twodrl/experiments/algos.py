"""Algorithm names of the experiment runner: the package's table :data:`sb3_twodrl.ALGOS`."""

from __future__ import annotations

from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_twodrl import ALGOS


def algo_class(name: str) -> type[BaseAlgorithm]:
    """The class registered as ``name`` in :data:`sb3_twodrl.ALGOS`."""
    if name not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {name!r}")
    return ALGOS[name]
