"""The bench's algorithms, plain subclasses of the library's and SB3's, and the names specs give them (:data:`ALGOS`):
the package's table :data:`sb3_twodrl.ALGOS`, the stock arms on the fast path (:mod:`.baselines`, SB3's numbers
bit for bit), the ablation's variants (:mod:`.variants`) and the self-tuning entropy arms (:mod:`.auto_entropy`)."""

from __future__ import annotations

from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_twodrl import ALGOS as PACKAGE_ALGOS
from twodrl_bench.algorithms.auto_entropy import AUTO_ENTROPY_ALGOS
from twodrl_bench.algorithms.baselines import BASELINE_ALGOS
from twodrl_bench.algorithms.variants import VARIANT_ALGOS

ALGOS: dict[str, type[BaseAlgorithm]] = {**PACKAGE_ALGOS, **BASELINE_ALGOS, **VARIANT_ALGOS, **AUTO_ENTROPY_ALGOS}
"""Every algorithm the experiment commands can run, by name."""


def algo_class(name: str) -> type[BaseAlgorithm]:
    """The class registered as ``name`` in :data:`ALGOS`."""
    if name not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {name!r}")
    return ALGOS[name]
