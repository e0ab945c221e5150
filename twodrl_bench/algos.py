"""Algorithm names of the experiment runner: the package's table :data:`sb3_twodrl.ALGOS`, its stock arms on
the fast path (:data:`twodrl_bench.baselines.BASELINE_ALGOS`, SB3's numbers bit for bit) and the
ablation's variants (:data:`twodrl_bench.variants.VARIANT_ALGOS`) and the self-tuning entropy baselines
(:data:`twodrl_bench.auto_entropy.AUTO_ENTROPY_ALGOS`)."""

from __future__ import annotations

from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_twodrl import ALGOS as PACKAGE_ALGOS
from twodrl_bench.auto_entropy import AUTO_ENTROPY_ALGOS
from twodrl_bench.baselines import BASELINE_ALGOS
from twodrl_bench.variants import VARIANT_ALGOS

ALGOS: dict[str, type[BaseAlgorithm]] = {**PACKAGE_ALGOS, **BASELINE_ALGOS, **VARIANT_ALGOS, **AUTO_ENTROPY_ALGOS}
"""Every algorithm the experiment commands can run, by name."""


def algo_class(name: str) -> type[BaseAlgorithm]:
    """The class registered as ``name`` in :data:`ALGOS`."""
    if name not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {name!r}")
    return ALGOS[name]
