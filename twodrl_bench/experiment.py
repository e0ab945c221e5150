"""The study object: a spec resolved once into every setting of its runs, and the jobs it makes.

:meth:`Experiment.from_spec` reads a spec (:mod:`twodrl_bench.spec`: the YAML layer), reads each arm's
settings (the env's entry of ``<algo>.yml``: packaged, rl-zoo3's own or in a folder) and applies its
overrides, once; the result is frozen and holds everything a run needs. The defaults of a protocol are
stated once, in its dataclass (:class:`EpochProtocol`, :class:`TimestepsProtocol`). The flow goes one way:
the runner (:mod:`twodrl_bench.runner`) builds an :class:`Experiment`, the experiment makes its
:class:`Job` objects, the runner runs each by its protocol's module, which resumes it by :mod:`twodrl_bench.jobs`.

"Same run?" is decided in one place, :func:`deciding`: a run folder's stored experiment and a new one must
agree on it for their common arms (:meth:`Experiment.differences`), and a job's checkpoint must agree on
its job's part of it (:meth:`Job.identity`) to be resumed.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from twodrl_bench.settings import check_constants, class_defaults, epoch_entry, settings_file, timesteps_entry
from twodrl_bench.spec import FIELDS, Spec, diff, load_spec, validate

RUN_OPTIONS = ("checkpoint_every", "save_model", "tensorboard")
"""Protocol keys that change what a run keeps, not its rows: free to change between invocations."""
FREE = ("name", "rules", "report", "seeds")
"""Top-level fields that may change between invocations on one folder (seeds may be added)."""
PAPER_TRIALS = 10
"""Trials on the real robot per policy in the paper (section 3.5): the first of a transfer's trials."""
TRANSFER_SEED = 1_000_003
"""The held-out seed of a transfer's trials (sub-env ``i`` seeded ``seed + i``); its own env's: ``seed + 10**4``."""


def _positive_int(key: str, value: Any, zero: bool = False) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < (0 if zero else 1):
        raise ValueError(f"{key} {'must be an int >= 0' if zero else 'must be a positive int'}, got {value!r}")
    return value


@dataclass(frozen=True)
class EpochProtocol:
    """The paper's epochs (section 3.4.1): ``epochs`` of ``learn_episodes`` (K) learning trials, each followed by
    ``test_episodes`` (M) test trials; run by :mod:`twodrl_bench.epochs`.

    ``vec_env``: ``auto``, ``batched`` or ``dummy`` (:mod:`twodrl_bench.vec_env`); ``checkpoint_every``: epochs
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
            _positive_int(f"protocol.{key}", getattr(self, key))
        _positive_int("protocol.checkpoint_every", self.checkpoint_every, zero=True)
        if self.transfer is not None:
            object.__setattr__(self, "transfer", _transfer(self.transfer, self.save_model))

    @classmethod
    def from_mapping(cls, raw: dict[str, Any]) -> EpochProtocol:
        """:raises ValueError: naming the key, for an unknown, missing or ill-typed key"""
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(raw) - set(names))
        if unknown:
            raise ValueError(f"protocol of epochs takes only {names}, got {unknown!r}")
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


def _transfer(transfer: Any, save_model: bool) -> dict[str, Any]:
    """``{env, trials, seed}`` of a transfer (seed defaults to the held-out one), checked."""
    key = "protocol.transfer"
    ok = isinstance(transfer, dict) and {"env", "trials"} <= set(transfer) <= {"env", "trials", "seed"}
    if not ok or not isinstance(transfer["env"], str):
        raise ValueError(f"{key} must be {{env: <Gymnasium ID>, trials: <int>, seed: <int>}}, got {transfer!r}")
    if _positive_int(f"{key}.trials", transfer["trials"]) < PAPER_TRIALS:
        raise ValueError(f"{key}.trials must be at least the paper's {PAPER_TRIALS}, got {transfer['trials']!r}")
    transfer = {**transfer, "seed": transfer.get("seed", TRANSFER_SEED)}
    _positive_int(f"{key}.seed", transfer["seed"], zero=True)
    if not save_model:
        raise ValueError("protocol.save_model must be true with a transfer (its trials load the model), got False")
    return transfer


@dataclass(frozen=True)
class TimestepsProtocol:
    """A budget of ``timesteps`` (None: the entry's ``n_timesteps``) trained by rl-zoo3, then ``eval_episodes``
    deterministic episodes; run by :mod:`twodrl_bench.timesteps` (whose docstring describes ``events``,
    ``entry`` and ``task``). ``checkpoint_every``: timesteps between checkpoints (0: none)."""

    timesteps: int | None
    eval_episodes: int
    events: str | None = None
    entry: str | None = None
    task: str | None = None
    checkpoint_every: int = 20_000

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
        _positive_int("protocol.checkpoint_every", self.checkpoint_every, zero=True)

    @classmethod
    def from_mapping(cls, raw: dict[str, Any]) -> TimestepsProtocol:
        """:raises ValueError: naming the key, for an unknown key or a bad budget, episode count or label"""
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(raw) - set(names))
        if unknown:
            raise ValueError(f"protocol: the timesteps protocol takes only {names}, got {unknown}")
        return cls(**{"timesteps": None, "eval_episodes": None, **raw})

    def as_dict(self) -> dict[str, Any]:
        """The protocol as a spec holds it (unset optional labels left out)."""
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None or k == "timesteps"}


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


@dataclass(frozen=True)
class Arm:
    """One arm, resolved: ``hyperparams`` (its settings' entry with ``override`` over it) and ``defaults`` (the
    constructor defaults of ``algo`` in force, as ``repr``)."""

    name: str
    algo: str
    override: dict[str, Any]
    settings: str
    hyperparams: dict[str, Any]
    defaults: dict[str, str]

    @classmethod
    def resolve(cls, name: str, arm: dict[str, Any], env: str, protocol: Protocol) -> Arm:
        """The arm ``{algo, override, settings}`` of a validated spec, its settings read.

        :raises ValueError: if a settings file or its entry is missing, or (epochs) holds a schedule
        """
        if isinstance(protocol, TimestepsProtocol):
            hyperparams = timesteps_entry(arm, env, protocol.as_dict())
        else:
            entry = epoch_entry(settings_file(arm["algo"], arm["settings"]), env)
            hyperparams = {**entry, **arm["override"]}
            check_constants(hyperparams, f"arms.{name}")
        defaults = class_defaults(arm["algo"], hyperparams)
        return cls(name, arm["algo"], dict(arm["override"]), arm["settings"], hyperparams, defaults)

    def as_dict(self) -> dict[str, Any]:
        """The arm as a resolved spec holds it."""
        out = dataclasses.asdict(self)
        del out["name"]
        return out


@dataclass(frozen=True)
class Experiment:
    """Every setting of a study's runs, resolved once (:meth:`from_spec`); fields as ``docs/studies.md`` lists."""

    name: str
    env: str
    env_kwargs: dict[str, Any]
    gym_packages: tuple[str, ...]
    protocol: Protocol
    seeds: tuple[int, ...]
    arms: dict[str, Arm]
    report: str | None
    rules: dict[str, Any] = field(default_factory=dict)
    grid: dict[str, Any] | None = None

    @classmethod
    def from_spec(cls, spec: str | Path | Spec) -> Experiment:
        """The experiment of ``spec``: a packaged spec's name, a path, or a spec mapping (:func:`~.spec.validate`).

        :raises ValueError: naming the field, for a bad spec or missing settings
        """
        validated = validate(spec) if isinstance(spec, dict) else load_spec(spec)
        protocol = protocol_of(validated["protocol"])
        arms = {name: Arm.resolve(name, arm, validated["env"], protocol) for name, arm in validated["arms"].items()}
        return cls._of(validated, protocol, arms)

    @classmethod
    def from_resolved(cls, resolved: Spec) -> Experiment:
        """The experiment a run folder's ``spec.yml`` holds (its arms already resolved)."""
        arms = {name: Arm(name=name, **arm) for name, arm in resolved["arms"].items()}
        return cls._of(resolved, protocol_of(resolved["protocol"]), arms)

    @classmethod
    def _of(cls, spec: Spec, protocol: Protocol, arms: dict[str, Arm]) -> Experiment:
        return cls(
            name=spec["name"],
            env=spec["env"],
            env_kwargs=dict(spec["env_kwargs"]),
            gym_packages=tuple(spec["gym_packages"]),
            protocol=protocol,
            seeds=tuple(spec["seeds"]),
            arms=arms,
            report=spec.get("report"),
            rules=dict(spec.get("rules") or {}),
            grid=copy.deepcopy(spec.get("grid")),
        )

    def as_dict(self) -> Spec:
        """The resolved spec (what a run folder's ``spec.yml`` holds), fields in order."""
        out = {
            "name": self.name,
            "env": self.env,
            "env_kwargs": copy.deepcopy(self.env_kwargs),
            "gym_packages": list(self.gym_packages),
            "protocol": self.protocol.as_dict(),
            "seeds": list(self.seeds),
            "arms": {name: arm.as_dict() for name, arm in self.arms.items()},
            "grid": copy.deepcopy(self.grid),
            "rules": copy.deepcopy(self.rules),
            "report": self.report,
        }
        return {key: out[key] for key in FIELDS if out[key] is not None}

    def differences(self, stored: Experiment) -> list[str]:
        """What differs between ``stored`` and this experiment in what decides the rows of their common arms."""
        common = set(stored.arms) & set(self.arms)
        return diff(deciding(stored.as_dict(), common), deciding(self.as_dict(), common))

    def merged(self, stored: Experiment) -> Experiment:
        """This experiment with the arms and seeds only ``stored`` has (what a folder holds after both ran into it)."""
        seeds = tuple(sorted(set(stored.seeds) | set(self.seeds)))
        return dataclasses.replace(self, arms={**stored.arms, **self.arms}, seeds=seeds)

    def jobs(self, out_dir: str | Path, arms: list[str] | None = None) -> list[Job]:
        """The job of every (arm, seed) (only ``arms`` if given), writing under ``out_dir``.

        :raises ValueError: for an arm the experiment does not have
        """
        unknown = sorted(set(arms or []) - set(self.arms))
        if unknown:
            raise ValueError(f"arms must be among the spec's {list(self.arms)}, got {unknown}")
        return [Job(self, name, seed, str(out_dir)) for name in arms or self.arms for seed in self.seeds]


def deciding(spec: Spec, arms: set[str]) -> Spec:
    """What decides the rows of the jobs of ``arms`` in a resolved spec: every field but :data:`FREE`, the
    protocol without its :data:`RUN_OPTIONS`, and those arms."""
    out = {k: copy.deepcopy(v) for k, v in spec.items() if k not in FREE}
    out["protocol"] = {k: v for k, v in spec["protocol"].items() if k not in RUN_OPTIONS}
    out["arms"] = {k: copy.deepcopy(v) for k, v in spec["arms"].items() if k in arms}
    return out


@dataclass(frozen=True)
class Job:
    """One (arm, seed) of an experiment, writing under ``out_dir``; run by :func:`twodrl_bench.runner.run_job`."""

    experiment: Experiment
    arm_name: str
    seed: int
    out_dir: str

    def __post_init__(self) -> None:
        if self.arm_name not in self.experiment.arms:
            raise ValueError(f"arm_name must be one of {list(self.experiment.arms)}, got {self.arm_name!r}")
        _positive_int("seed", self.seed, zero=True)

    @property
    def arm(self) -> Arm:
        return self.experiment.arms[self.arm_name]

    @property
    def protocol(self) -> Protocol:
        return self.experiment.protocol

    @property
    def name(self) -> str:
        """``<arm>_seed<seed>``: the name of its rows, checkpoint, model and logs."""
        return f"{self.arm_name}_seed{self.seed}"

    def identity(self) -> Spec:
        """What its checkpoint must agree on to be resumed: :func:`deciding` of its arm, with its seed, without
        the protocol's ``extendable`` keys."""
        out = deciding(self.experiment.as_dict(), {self.arm_name})
        out["protocol"] = {k: v for k, v in out["protocol"].items() if k not in self.protocol.extendable}
        out["seed"] = self.seed
        return out
