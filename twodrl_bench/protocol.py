"""The protocols of a study (:class:`EpochProtocol`, :class:`TimestepsProtocol`, their defaults stated once) and
what an epoch job's rows hold (section 3.4.1): the CSV columns and the test trials' seeds.

An *epoch* is K learning trials (episodes; paper: 1000) followed by M test trials (paper: 100)
with other random numbers (:class:`~twodrl_bench.protocol.EpochProtocol`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

ROUTES = ("shortcut", "detour")
"""The route labels an env reports in ``info["route"]`` whose shares are columns (section 3.4.1), even when no test
trial took one: the office's route regions (``twodrl_envs.nomad.geometry.ROUTE_REGIONS``), met by value as env IDs
are (tested), not imported."""
METRICS = ("goal_rate", "reward_per_step", *(f"{route}_share" for route in ROUTES), "collision_rate")
LEARNING = ("interest_share", "mean_temperature")
"""Per epoch, over the learning steps of the rollouts that ended in it: the share of actions whose
temperature the interest (not a clamp) set, and the mean temperature (NaN for stock SB3 algorithms)."""
COLUMNS = ["env", "algo", "seed", "epoch", "learn_episodes", *METRICS, *LEARNING, "env_steps", "wall_s"]


def trial_seed(seed: int, epoch: int) -> int:
    """Seed of epoch ``epoch``'s test trials: disjoint from the learning seeds (which are < 10**6)."""
    return 10**6 + 1_000 * (seed % 10**6) + epoch


PAPER_TRIALS = 10
"""Trials on the real robot per policy in the paper (section 3.5): the first of a transfer's trials."""
TRANSFER_SEED = 1_000_003
"""The held-out seed of a transfer's trials (sub-env ``i`` seeded ``seed + i``); its own env's: ``seed + 10**4``."""


def positive_int(key: str, value: Any, zero: bool = False) -> int:
    """``value`` if it is an int >= 1 (>= 0 with ``zero``), else ``ValueError`` naming ``key``."""
    if isinstance(value, bool) or not isinstance(value, int) or value < (0 if zero else 1):
        raise ValueError(f"{key} {'must be an int >= 0' if zero else 'must be a positive int'}, got {value!r}")
    return value


@dataclass(frozen=True)
class EpochProtocol:
    """The paper's epochs (section 3.4.1): ``epochs`` of ``learn_episodes`` (K) learning trials, each followed by
    ``test_episodes`` (M) test trials; run by :mod:`twodrl_bench.epochs`.

    ``vec_env``: ``auto``, ``batched`` or ``dummy`` (:mod:`twodrl_zoo.vec_env`); ``checkpoint_every``: epochs
    between checkpoints (0: none); ``transfer``: ``{env, trials, seed}``, the final policy's trials on another env.
    """

    epochs: int
    learn_episodes: int
    test_episodes: int
    vec_env: str = "auto"
    checkpoint_every: int = 10
    save_model: bool = True
    tensorboard: bool = True
    transfer: dict[str, Any] | None = None

    module: ClassVar[str] = "twodrl_bench.epochs"
    extendable: ClassVar[tuple[str, ...]] = ("epochs",)
    """Keys a checkpoint may differ in and still be resumed: a shorter run's checkpoint extends to a longer run."""

    def __post_init__(self) -> None:
        for key in ("epochs", "learn_episodes", "test_episodes"):
            positive_int(f"protocol.{key}", getattr(self, key))
        positive_int("protocol.checkpoint_every", self.checkpoint_every, zero=True)
        if self.transfer is not None:
            object.__setattr__(self, "transfer", _transfer(self.transfer, self.save_model))

    @classmethod
    def from_mapping(cls, raw: dict[str, Any]) -> EpochProtocol:
        """:raises ValueError: naming the key, for an unknown, missing or ill-typed key"""
        _check_fields(cls, raw, "epochs")
        for key in ("epochs", "learn_episodes", "test_episodes"):
            if key not in raw:
                raise ValueError(f"protocol.{key} is missing (protocol: {raw!r})")
        return cls(**raw)

    def as_dict(self) -> dict[str, Any]:
        """The protocol as a spec holds it (no ``transfer`` key without one)."""
        out = dataclasses.asdict(self)
        if out["transfer"] is None:
            del out["transfer"]
        return out


def _check_fields(cls: type, raw: dict[str, Any], label: str) -> None:
    """``ValueError`` naming the keys of ``raw`` that are no field of the protocol dataclass ``cls``."""
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(raw) - set(names))
    if unknown:
        raise ValueError(f"protocol of {label} takes only {names}, got {unknown}")


def _transfer(transfer: Any, save_model: bool) -> dict[str, Any]:
    """``{env, trials, seed, env_kwargs}`` of a transfer (seed defaults to the held-out one; ``env_kwargs``, the
    transfer env's options, to the training env's), checked."""
    key = "protocol.transfer"
    ok = isinstance(transfer, dict) and {"env", "trials"} <= set(transfer) <= {"env", "trials", "seed", "env_kwargs"}
    if not ok or not isinstance(transfer["env"], str) or not isinstance(transfer.get("env_kwargs", {}), dict):
        raise ValueError(
            f"{key} must be {{env: <Gymnasium ID>, trials: <int>, seed: <int>, env_kwargs: <mapping>}}, "
            f"got {transfer!r}"
        )
    if positive_int(f"{key}.trials", transfer["trials"]) < PAPER_TRIALS:
        raise ValueError(f"{key}.trials must be at least the paper's {PAPER_TRIALS}, got {transfer['trials']!r}")
    transfer = {**transfer, "seed": transfer.get("seed", TRANSFER_SEED)}
    positive_int(f"{key}.seed", transfer["seed"], zero=True)
    if not save_model:
        raise ValueError("protocol.save_model must be true with a transfer (its trials load the model), got False")
    return transfer


def _stand_ins(stand_ins: Any) -> dict[str, Any]:
    """``{trials, seed, env_kwargs}`` of the trials on both stand-in robots (seed defaults to the transfer's)."""
    key = "protocol.stand_ins"
    if not isinstance(stand_ins, dict) or not {"trials"} <= set(stand_ins) <= {"trials", "seed", "env_kwargs"}:
        raise ValueError(f"{key} must be {{trials: <int>, seed: <int>, env_kwargs: <mapping>}}, got {stand_ins!r}")
    if not isinstance(stand_ins.get("env_kwargs", {}), dict):
        raise ValueError(f"{key}.env_kwargs must be a mapping, got {stand_ins['env_kwargs']!r}")
    positive_int(f"{key}.trials", stand_ins["trials"])
    stand_ins = {**stand_ins, "seed": stand_ins.get("seed", TRANSFER_SEED)}
    positive_int(f"{key}.seed", stand_ins["seed"], zero=True)
    return stand_ins


@dataclass(frozen=True)
class TimestepsProtocol:
    """A budget of ``timesteps`` (None: the entry's ``n_timesteps``) trained by rl-zoo3, then ``eval_episodes``
    deterministic episodes; run by :mod:`twodrl_bench.timesteps` (whose docstring describes ``events``,
    ``entry``, ``task``, ``check_every``, ``check_episodes``, ``keep_learned`` and ``transfer``).
    ``checkpoint_every``: timesteps between checkpoints (0: none)."""

    timesteps: int | None
    eval_episodes: int
    events: str | None = None
    entry: str | None = None
    task: str | None = None
    checkpoint_every: int = 20_000
    check_every: int = 0
    check_episodes: int = 5
    keep_learned: bool = False
    transfer: dict[str, Any] | None = None
    stand_ins: dict[str, Any] | None = None

    module: ClassVar[str] = "twodrl_bench.timesteps"
    extendable: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self) -> None:
        if self.timesteps is not None:
            timesteps = self.timesteps
            if not isinstance(timesteps, int) or isinstance(timesteps, bool) or timesteps < 1:
                raise ValueError(f"protocol.timesteps must be an int >= 1 or null, got {timesteps!r}")
        episodes = self.eval_episodes
        if not isinstance(episodes, int) or isinstance(episodes, bool) or episodes < 1:
            raise ValueError(f"protocol.eval_episodes must be an int >= 1, got {episodes!r}")
        for key in ("events", "entry", "task"):
            if getattr(self, key) is not None and not isinstance(getattr(self, key), str):
                raise ValueError(f"protocol.{key} must be a string or null, got {getattr(self, key)!r}")
        positive_int("protocol.checkpoint_every", self.checkpoint_every, zero=True)
        positive_int("protocol.check_every", self.check_every, zero=True)
        positive_int("protocol.check_episodes", self.check_episodes)
        if not isinstance(self.keep_learned, bool):
            raise ValueError(f"protocol.keep_learned must be true or false, got {self.keep_learned!r}")
        if self.keep_learned and not self.check_every:
            raise ValueError("protocol.keep_learned needs protocol.check_every > 0 (the checks it keeps from)")
        if self.transfer is not None:
            object.__setattr__(self, "transfer", _transfer(self.transfer, True))
        if self.stand_ins is not None:
            object.__setattr__(self, "stand_ins", _stand_ins(self.stand_ins))

    @classmethod
    def from_mapping(cls, raw: dict[str, Any]) -> TimestepsProtocol:
        """:raises ValueError: naming the key, for an unknown key or a bad budget, episode count or label"""
        _check_fields(cls, raw, "timesteps")
        return cls(**{"timesteps": None, "eval_episodes": None, **raw})

    def as_dict(self) -> dict[str, Any]:
        """The protocol as a spec holds it (unset optional labels, and checks and transfer where there are none, left
        out: the specs of earlier runs stay as they were)."""
        out = {k: v for k, v in dataclasses.asdict(self).items() if v is not None or k == "timesteps"}
        if not self.check_every:
            del out["check_every"], out["check_episodes"]
        if not self.keep_learned:
            del out["keep_learned"]
        return out


Protocol = EpochProtocol | TimestepsProtocol


def protocol_of(raw: Any) -> Protocol:
    """The protocol of a spec's ``protocol`` mapping: epochs if it has ``epochs``, timesteps if it has both
    ``timesteps`` and ``eval_episodes``.

    :raises ValueError: naming the key and its value
    """
    if not isinstance(raw, dict):
        raise ValueError(f"protocol must be a mapping, got {raw!r}")
    if "epochs" in raw:
        return EpochProtocol.from_mapping(raw)
    if "timesteps" in raw and "eval_episodes" in raw:
        return TimestepsProtocol.from_mapping(raw)
    raise ValueError(
        f"protocol must be {{epochs, learn_episodes, test_episodes}} or {{timesteps, eval_episodes}}, got {raw!r}"
    )
