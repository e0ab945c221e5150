"""The study object: a spec resolved once into every setting of its runs, and the jobs it makes.

:meth:`Experiment.from_spec` reads a spec (:mod:`twodrl_bench.spec`: the YAML layer), reads each arm's
settings (the env's entry of ``<algo>.yml``: packaged, rl-zoo3's own or in a folder) and applies its
overrides, once; the result is frozen and holds everything a run needs. The defaults of a protocol are
stated once, in its dataclass (:class:`~twodrl_bench.protocol.EpochProtocol`,
:class:`~twodrl_bench.protocol.TimestepsProtocol`). The flow goes one way:
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
from typing import Any

from twodrl_bench.protocol import Protocol, TimestepsProtocol, positive_int, protocol_of
from twodrl_bench.settings import check_constants, class_defaults, epoch_entry, settings_file, timesteps_entry
from twodrl_bench.spec import FIELDS, Spec, diff, load_spec, validate
from twodrl_zoo.hyperparams import resolve

RUN_OPTIONS = ("checkpoint_every", "save_model", "tensorboard")
"""Protocol keys that change what a run keeps, not its rows: free to change between invocations."""
FREE = ("name", "rules", "report", "seeds")
"""Top-level fields that may change between invocations on one folder (seeds may be added)."""


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
            hyperparams = resolve(entry, None, arm["override"]).entry
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


SEED = "{seed}"
"""What a string value of ``env_kwargs`` may hold to name the job's seed (:attr:`Job.env_kwargs`)."""


def with_seed(value: Any, seed: int) -> Any:
    """``value`` (a mapping, list or scalar of a spec) with :data:`SEED` in each string replaced by ``seed``."""
    if isinstance(value, dict):
        return {key: with_seed(item, seed) for key, item in value.items()}
    if isinstance(value, list):
        return [with_seed(item, seed) for item in value]
    return value.replace(SEED, str(seed)) if isinstance(value, str) else value


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
        positive_int("seed", self.seed, zero=True)

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

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """The experiment's ``env_kwargs`` for this job: ``{seed}`` in a string value becomes the job's seed (one
        env per seed, e.g. ``map: "generated:S:{seed}"``: a seed list is then a list of offices)."""
        return with_seed(self.experiment.env_kwargs, self.seed)

    def identity(self) -> Spec:
        """What its checkpoint must agree on to be resumed: :func:`deciding` of its arm, with its seed, without
        the protocol's ``extendable`` keys."""
        out = deciding(self.experiment.as_dict(), {self.arm_name})
        out["protocol"] = {k: v for k, v in out["protocol"].items() if k not in self.protocol.extendable}
        out["seed"] = self.seed
        return out
