"""The paper's protocol (section 3.4.1) as data: presets, run specs, hyperparameter files, CSV columns.

An *epoch* is K learning trials (episodes; paper: 1000) followed by M test trials (paper: 100)
with other random numbers; S seeds per algorithm.
"""

from __future__ import annotations

import inspect
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from sb3_twodrl.hyperparams import evaluate, read_entry

ROUTES = ("shortcut", "detour")
"""The office's route labels (``info["route"]``), whose shares are columns even when no test trial took one."""
METRICS = ("goal_rate", "reward_per_step", *(f"{route}_share" for route in ROUTES), "collision_rate")
LEARNING = ("interest_share", "mean_temperature")
"""Per epoch, over the learning steps of the rollouts that ended in it: the share of actions whose
temperature the interest (not a clamp) set, and the mean temperature (NaN for stock SB3 algorithms)."""
COLUMNS = ["env", "algo", "seed", "epoch", "learn_episodes", *METRICS, *LEARNING, "env_steps", "wall_s"]
PRESETS: dict[str, dict[str, int]] = {
    # epochs, learning trials per epoch (K), test trials per epoch (M), seeds (S)
    "tiny": {"epochs": 3, "learn_episodes": 8, "test_episodes": 4, "seeds": 2},
    "quick": {"epochs": 30, "learn_episodes": 1000, "test_episodes": 100, "seeds": 5},
    "paper": {"epochs": 1000, "learn_episodes": 1000, "test_episodes": 100, "seeds": 5},
}
ZOO_ONLY = ("n_timesteps", "callback", "normalize", "env_wrapper", "vec_env_wrapper", "frame_stack")
_NOT_SETTINGS = ("policy", "env", "verbose", "seed", "device", "tensorboard_log", "_init_setup_model")


def class_defaults(algo: str, hyperparams: dict[str, Any]) -> dict[str, str]:
    """The constructor defaults of ``algo``'s class that ``hyperparams`` leave in force, as ``repr``:
    a run resumed after a default changed (a new release) is then refused, not mixed."""
    from twodrl_bench.algos import algo_class

    parameters = inspect.signature(algo_class(algo).__init__).parameters.values()
    return {
        p.name: repr(p.default)
        for p in parameters
        if p.default is not p.empty and p.name not in _NOT_SETTINGS and p.name not in hyperparams
    }


@dataclass
class RunSpec:
    """Everything one (algo, seed) run needs; plain data, so it travels to a worker process or a Ray task.

    ``vec_env``: ``"auto"`` (the registry's batched env where there is one), ``"batched"`` or
    ``"dummy"`` (SB3's ``DummyVecEnv``); see :mod:`twodrl_bench.vec_env`.
    ``checkpoint_every``: epochs between checkpoints (0: none). ``env_kwargs``: passed to the env's
    constructor for learning and test trials alike (e.g. ``{"observe_odometry": False}``). ``label``: the
    run's name instead of the algorithm's (a study's arm: two arms may run one algorithm).
    """

    env_id: str
    algo: str
    seed: int
    epochs: int
    learn_episodes: int
    test_episodes: int
    hyperparams: dict[str, Any]
    out_dir: str
    gym_packages: list[str] = field(default_factory=list)
    vec_env: str = "auto"
    checkpoint_every: int = 10
    save_model: bool = True
    tensorboard: bool = True
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    label: str = ""

    def __post_init__(self) -> None:
        for name in ("epochs", "learn_episodes", "test_episodes"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive int, got {value!r}")
        if isinstance(self.checkpoint_every, bool) or not isinstance(self.checkpoint_every, int):
            raise ValueError(f"checkpoint_every must be an int >= 0, got {self.checkpoint_every!r}")
        if self.checkpoint_every < 0:
            raise ValueError(f"checkpoint_every must be an int >= 0, got {self.checkpoint_every!r}")

    @property
    def name(self) -> str:
        return f"{self.label or self.algo}_seed{self.seed}"

    def protocol(self) -> dict[str, Any]:
        """What a checkpoint must agree on to be resumed by this spec (all but paths, length and outputs),
        the algorithm's defaults in force included."""
        keep = ("env_id", "algo", "seed", "learn_episodes", "test_episodes", "vec_env", "env_kwargs")
        out = {k: v for k, v in asdict(self).items() if k in keep}
        out["hyperparams"] = {k: repr(v) for k, v in sorted(self.hyperparams.items())}
        out["defaults"] = class_defaults(self.algo, self.hyperparams)
        return out


def epoch_entry(path: str | Path, env_id: str) -> dict[str, Any]:
    """The ``env_id`` entry of an rl-zoo3 hyperparameter file (:func:`~sb3_twodrl.hyperparams.read_entry`) as
    written, without the keys only rl-zoo3 uses (``n_timesteps``, ``callback``, ...).

    :raises ValueError: if the file does not exist or has no entry for ``env_id``
    """
    return {k: v for k, v in read_entry(path, env_id).items() if k not in ZOO_ONLY}


def check_constants(hyperparams: dict[str, Any], where: str) -> None:
    """Refuse a schedule (``lin_...``): an epoch protocol has no total budget to schedule over.

    :raises ValueError: naming ``where``, the key and the value
    """
    for key, value in hyperparams.items():
        if isinstance(value, str) and value.startswith(("lin_", "linear_")):
            raise ValueError(f"{where}: {key} is a schedule ({value!r}); the epoch protocol takes constants")


def load_hyperparams(path: str | Path, env_id: str) -> dict[str, Any]:
    """:func:`epoch_entry` with a ``policy_kwargs`` string evaluated as rl-zoo3 does
    (:func:`~sb3_twodrl.hyperparams.evaluate`) and schedules refused (:func:`check_constants`).

    :raises ValueError: if the file does not exist, has no entry for ``env_id`` or holds a schedule
    """
    entry = epoch_entry(path, env_id)
    if isinstance(entry.get("policy_kwargs"), str):
        entry["policy_kwargs"] = evaluate(entry["policy_kwargs"])
    check_constants(entry, str(path))
    return entry


def parse_env_kwargs(items: list[str] | None, name: str = "env_kwargs") -> dict[str, Any]:
    """``["key:value", ...]`` (rl-zoo3's ``--env-kwargs`` format, values as Python literals) as a dict;
    ``name`` is the option named in the error."""
    import ast

    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition(":")
        try:
            if not (sep and key.isidentifier()):
                raise ValueError
            out[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            raise ValueError(f"{name} items must be key:value with a Python literal value, got {item!r}") from None
    return out


def trial_seed(seed: int, epoch: int) -> int:
    """Seed of epoch ``epoch``'s test trials: disjoint from the learning seeds (which are < 10**6)."""
    return 10**6 + 1_000 * (seed % 10**6) + epoch


SETTINGS_SUFFIXES = ("_variant", "_auto")
"""An algorithm named ``<algo><suffix>`` (an ablation variant, a self-tuning arm) reads ``<algo>``'s settings."""


def settings_algo(algo: str) -> str:
    """The algorithm whose settings file ``algo`` reads (:data:`SETTINGS_SUFFIXES`)."""
    for suffix in SETTINGS_SUFFIXES:
        algo = algo.removesuffix(suffix)
    return algo
