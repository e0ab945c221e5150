"""The bench's algorithms, plain subclasses of the library's and SB3's, and the names specs give them (:data:`ALGOS`):
the package's table :data:`sb3_twodrl.ALGOS`, the stock algorithms on the fast path (:mod:`.baselines`, SB3's numbers
bit for bit), the ablation's variants (:mod:`.variants`) and the self-tuning entropy arms (:mod:`.auto_entropy`).

A name means one class everywhere: ``a2c`` is SB3's ``A2C`` here, in the library, in rl-zoo3 and in both protocols'
rows. The epoch protocol trains a stock arm on the fast path (:data:`FAST_PATH`, :func:`epoch_class`), the same
numbers in less time (``tests/bench/test_fast.py``), under the arm's own ``algo`` label.
"""

from __future__ import annotations

from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_twodrl import ALGOS as PACKAGE_ALGOS
from twodrl_bench.algorithms.auto_entropy import AUTO_ENTROPY_ALGOS
from twodrl_bench.algorithms.baselines import BASELINE_ALGOS
from twodrl_bench.algorithms.variants import VARIANT_ALGOS

ALGOS: dict[str, type[BaseAlgorithm]] = {**PACKAGE_ALGOS, **BASELINE_ALGOS, **VARIANT_ALGOS, **AUTO_ENTROPY_ALGOS}
"""Every algorithm the experiment commands can run, by name (the tables it joins share no name)."""
FAST_PATH: dict[str, str] = {"a2c": "a2c_batched", "ppo": "ppo_batched"}
"""The name of the class the epoch protocol trains for a stock ``algo`` (SB3's numbers bit for bit, faster)."""


def algo_class(name: str) -> type[BaseAlgorithm]:
    """The class registered as ``name`` in :data:`ALGOS`."""
    if name not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {name!r}")
    return ALGOS[name]


def epoch_class(name: str) -> type[BaseAlgorithm]:
    """The class the epoch protocol trains for a spec's ``algo`` ``name``: its :data:`FAST_PATH` one if any."""
    return algo_class(FAST_PATH.get(name, name))
