"""Algorithm names of the experiment runner: ``name -> "module:Class"``, imported on first use."""

from __future__ import annotations

import importlib

from stable_baselines3.common.base_class import BaseAlgorithm

ALGOS: dict[str, str] = {
    "twoda2c": "sb3_twodrl:TwoDimA2C",
    "a2c": "stable_baselines3:A2C",
    "ppo": "stable_baselines3:PPO",
}


def algo_class(name: str) -> type[BaseAlgorithm]:
    """The class registered as ``name`` in :data:`ALGOS`."""
    if name not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {name!r}")
    module, cls = ALGOS[name].split(":")
    return getattr(importlib.import_module(module), cls)
