"""Studies as data: a spec (a YAML file) names an env, a protocol, seeds and arms; this module loads,
validates, resolves and compares specs.

A spec is packaged as ``twodrl_bench/specs/<study>.yml`` or, for a study of several parts,
``twodrl_bench/specs/<study>/<part>.yml``; its name is that path without ``.yml``. Fields
(``docs/studies.md``): ``name``, ``env``, ``env_kwargs`` ({}), ``gym_packages`` ([twodrl_envs]), ``protocol``
(the paper's epochs ``{epochs, learn_episodes, test_episodes}`` or ``{timesteps, eval_episodes}``),
``seeds``, ``arms`` (name -> ``{algo, override, settings}``) and/or ``grid`` (points that expand into arms,
kept in the spec for the report),
``rules`` (free-form, read by the report) and ``report`` (a module of :mod:`twodrl_bench.reports`, or a dotted
path; optional, default None: the runner writes the rows only).

*Resolving* a spec reads each arm's settings (the env's entry of ``<algo>.yml``, packaged or in the
arm's ``settings`` folder) and applies its overrides; the resolved spec also records the algorithms'
constructor defaults in force. Two resolved specs that differ in what decides the rows (:func:`guard_diff`)
must not share a run folder.
"""

from __future__ import annotations

import copy
import itertools
import re
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from sb3_twodrl.hyperparams import hyperparams_path

Spec = dict[str, Any]

FIELDS = ("name", "env", "env_kwargs", "gym_packages", "protocol", "seeds", "arms", "grid", "rules", "report")
EPOCH_PROTOCOL = {
    "epochs": None,
    "learn_episodes": None,
    "test_episodes": None,
    "vec_env": "auto",
    "checkpoint_every": 10,
    "save_model": True,
    "tensorboard": True,
    "transfer": None,
}
"""The epoch protocol's keys and their defaults (``None``: required, ``transfer`` optional)."""
TIMESTEPS_REQUIRED = ("timesteps", "eval_episodes")
RUN_OPTIONS = ("checkpoint_every", "save_model", "tensorboard")
"""Protocol keys that change what a run keeps, not its rows: free to change between invocations."""
FREE = ("name", "rules", "report", "seeds")
"""Top-level fields that may change between invocations on one folder (seeds may be added)."""
_ARM_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.=+-]*$")


def packaged_specs() -> list[str]:
    """The names of the packaged specs, sorted."""
    root = Path(str(resources.files(__package__).joinpath("specs")))
    return sorted(str(p.relative_to(root).with_suffix("")) for p in root.rglob("*.yml"))


def spec_path(spec: str | Path) -> Path:
    """The file of ``spec``: an existing path, else the packaged spec of that name.

    :raises ValueError: if neither exists
    """
    path = Path(spec)
    if path.suffix in (".yml", ".yaml") and path.is_file():
        return path
    packaged = Path(str(resources.files(__package__).joinpath("specs", f"{spec}.yml")))
    if packaged.is_file():
        return packaged
    raise ValueError(f"spec {str(spec)!r} is neither a .yml file nor a packaged spec (packaged: {packaged_specs()})")


def load_spec(spec: str | Path) -> Spec:
    """The validated spec of a packaged name or a path (:func:`validate`); a packaged spec's name must be its path."""
    path = spec_path(spec)
    raw = yaml.safe_load(path.read_text())
    out = validate(raw, str(path))
    root = Path(str(resources.files(__package__).joinpath("specs")))
    if path.resolve().is_relative_to(root.resolve()):
        expected = str(path.resolve().relative_to(root.resolve()).with_suffix(""))
        if out["name"] != expected:
            raise ValueError(f"{path}: name must be the spec's path name {expected!r}, got {out['name']!r}")
    return out


def _fail(source: str, key: str, message: str, value: Any) -> ValueError:
    return ValueError(f"{source}: {key} {message}, got {value!r}")


def _mapping(source: str, key: str, value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise _fail(source, key, "must be a mapping", value)
    return value


def _positive_int(source: str, key: str, value: Any, zero: bool = False) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < (0 if zero else 1):
        raise _fail(source, key, "must be an int >= 0" if zero else "must be a positive int", value)
    return value


def validate(raw: Any, source: str = "spec") -> Spec:
    """``raw`` (a parsed YAML mapping) checked and completed with the defaults; ``grid`` expanded into arms.

    :raises ValueError: naming the field and its value, for a missing, unknown or ill-typed field
    """
    spec = copy.deepcopy(_mapping(source, "the spec", raw))
    unknown = sorted(set(spec) - set(FIELDS))
    if unknown:
        raise _fail(source, "fields", f"must be among {list(FIELDS)}", unknown)
    for key in ("name", "env", "protocol", "seeds"):
        if key not in spec:
            raise ValueError(f"{source}: the field {key!r} is missing")
    for key in ("name", "env"):
        if not isinstance(spec[key], str) or not spec[key]:
            raise _fail(source, key, "must be a non-empty string", spec[key])
    spec["report"] = spec.get("report")
    if spec["report"] is not None and (not isinstance(spec["report"], str) or not spec["report"]):
        raise _fail(source, "report", "must be a non-empty string (a report module) or absent", spec["report"])
    spec["env_kwargs"] = _mapping(source, "env_kwargs", spec.get("env_kwargs") or {})
    packages = spec.get("gym_packages", ["twodrl_envs"])
    if not isinstance(packages, list) or not all(isinstance(p, str) for p in packages):
        raise _fail(source, "gym_packages", "must be a list of module names", packages)
    spec["gym_packages"] = packages
    spec["protocol"] = _protocol(source, spec["protocol"])
    seeds = spec["seeds"]
    if not isinstance(seeds, list) or not seeds:
        raise _fail(source, "seeds", "must be a non-empty list of ints >= 0", seeds)
    for seed in seeds:
        _positive_int(source, "seeds", seed, zero=True)
    if len(set(seeds)) < len(seeds):
        raise _fail(source, "seeds", "must not repeat a seed", seeds)
    arms = dict(_mapping(source, "arms", spec.get("arms") or {}))
    if "grid" in spec:
        for name, arm in _expand_grid(source, spec["grid"]).items():
            if name in arms:
                raise _fail(source, "grid", f"expands into the arm {name!r}, which arms already has", name)
            arms[name] = arm
    if not arms:
        raise ValueError(f"{source}: the spec has no arms (give arms or grid)")
    spec["arms"] = {name: _arm(source, name, arm) for name, arm in arms.items()}
    spec["rules"] = _mapping(source, "rules", spec.get("rules") or {})
    return {key: spec[key] for key in FIELDS if key in spec}


def _protocol(source: str, protocol: Any) -> dict[str, Any]:
    protocol = dict(_mapping(source, "protocol", protocol))
    if "epochs" in protocol:
        unknown = sorted(set(protocol) - set(EPOCH_PROTOCOL))
        if unknown:
            raise _fail(source, "protocol", f"of epochs takes only {list(EPOCH_PROTOCOL)}", unknown)
        out = {key: protocol.get(key, default) for key, default in EPOCH_PROTOCOL.items()}
        for key in ("epochs", "learn_episodes", "test_episodes"):
            if key not in protocol:
                raise ValueError(f"{source}: protocol.{key} is missing (protocol: {protocol!r})")
            _positive_int(source, f"protocol.{key}", out[key])
        _positive_int(source, "protocol.checkpoint_every", out["checkpoint_every"], zero=True)
        if out["transfer"] is None:
            del out["transfer"]
        else:
            out["transfer"] = _transfer(source, out["transfer"], out["save_model"])
        return out
    if all(key in protocol for key in TIMESTEPS_REQUIRED):
        if protocol["timesteps"] is not None:
            _positive_int(source, "protocol.timesteps", protocol["timesteps"])
        _positive_int(source, "protocol.eval_episodes", protocol["eval_episodes"])
        return protocol
    raise _fail(
        source, "protocol", "must be {epochs, learn_episodes, test_episodes} or {timesteps, eval_episodes}", protocol
    )


def _transfer(source: str, transfer: Any, save_model: bool) -> dict[str, Any]:
    """``{env, trials, seed}`` of a transfer (seed defaults to the held-out one), checked."""
    from twodrl_bench.epochs import PAPER_TRIALS, TRANSFER_SEED

    key = "protocol.transfer"
    transfer = dict(_mapping(source, key, transfer))
    if not {"env", "trials"} <= set(transfer) <= {"env", "trials", "seed"} or not isinstance(transfer["env"], str):
        raise _fail(source, key, "must be {env: <Gymnasium ID>, trials: <int>, seed: <int>}", transfer)
    if _positive_int(source, f"{key}.trials", transfer["trials"]) < PAPER_TRIALS:
        raise _fail(source, f"{key}.trials", f"must be at least the paper's {PAPER_TRIALS}", transfer["trials"])
    transfer.setdefault("seed", TRANSFER_SEED)
    _positive_int(source, f"{key}.seed", transfer["seed"], zero=True)
    if not save_model:
        raise _fail(source, "protocol.save_model", "must be true with a transfer (its trials load the model)", False)
    return transfer


def _arm(source: str, name: Any, arm: Any) -> dict[str, Any]:
    if not isinstance(name, str) or not _ARM_NAME.match(name):
        raise _fail(source, "arms", "names must be letters, digits and _.=+- (a file name)", name)
    arm = dict(_mapping(source, f"arms.{name}", arm))
    unknown = sorted(set(arm) - {"algo", "override", "settings"})
    if unknown:
        raise _fail(source, f"arms.{name}", "takes only algo, override and settings", unknown)
    from twodrl_bench.algos import ALGOS

    if arm.get("algo") not in ALGOS:
        raise _fail(source, f"arms.{name}.algo", f"must be one of {sorted(ALGOS)}", arm.get("algo"))
    override = _mapping(source, f"arms.{name}.override", arm.get("override") or {})
    settings = arm.get("settings", "packaged")
    if not isinstance(settings, str):
        raise _fail(source, f"arms.{name}.settings", "must be 'packaged' or a folder of <algo>.yml", settings)
    return {"algo": arm["algo"], "override": override, "settings": settings}


def point_name(point: dict[str, Any]) -> str:
    """A grid point's arm name: ``key=value`` pairs in grid order."""
    return "_".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in point.items())


def _expand_grid(source: str, grid: Any) -> dict[str, dict[str, Any]]:
    """``{algo, points: {key: [values]}, override, settings}`` -> one arm per point of the product of ``points``."""
    grid = dict(_mapping(source, "grid", grid))
    unknown = sorted(set(grid) - {"algo", "points", "override", "settings"})
    if unknown:
        raise _fail(source, "grid", "takes only algo, points, override and settings", unknown)
    points = _mapping(source, "grid.points", grid.get("points"))
    if not points or not all(isinstance(v, list) and v for v in points.values()):
        raise _fail(source, "grid.points", "must map each setting to a non-empty list of values", points)
    arms = {}
    for values in itertools.product(*points.values()):
        point = dict(zip(points, values, strict=True))
        arm = {"algo": grid.get("algo"), "override": {**(grid.get("override") or {}), **point}}
        if "settings" in grid:
            arm["settings"] = grid["settings"]
        arms[point_name(point)] = arm
    return arms


def resolve(spec: Spec) -> Spec:
    """``spec`` with each arm's ``hyperparams`` and ``defaults`` (the constructor defaults in force, as ``repr``).

    Epochs: the env's entry of the arm's settings file, rl-zoo3's keys dropped, overrides applied. Timesteps:
    ``twodrl_bench.timesteps.resolve_arm``'s entry (rl-zoo3's files among the settings).

    :raises ValueError: if a settings file or its entry for the env is missing, or (epochs) holds a schedule
    """
    from twodrl_bench.protocol import check_constants, class_defaults, epoch_entry, settings_algo

    out = copy.deepcopy(spec)
    epochs = "epochs" in spec["protocol"]
    for name, arm in out["arms"].items():
        if not epochs:  # the timesteps job's own entries (rl-zoo3's files among them)
            from twodrl_bench.timesteps import resolve_arm

            arm["hyperparams"] = resolve_arm(arm, spec["env"], spec["protocol"])
            arm["defaults"] = class_defaults(arm["algo"], arm["hyperparams"])
            continue
        folder = None if arm["settings"] == "packaged" else arm["settings"]
        hyperparams = {
            **epoch_entry(hyperparams_path(settings_algo(arm["algo"]), folder), spec["env"]),
            **arm["override"],
        }
        check_constants(hyperparams, f"arms.{name}")
        arm["hyperparams"] = hyperparams
        arm["defaults"] = class_defaults(arm["algo"], hyperparams)
    return out


def diff(old: Any, new: Any, path: str = "") -> list[str]:
    """Every key path where ``old`` and ``new`` differ, as ``path: old != new`` (a missing key shows as <absent>)."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for key in [*old, *(k for k in new if k not in old)]:
            sub = f"{path}.{key}" if path else str(key)
            out += diff(old.get(key, _ABSENT), new.get(key, _ABSENT), sub)
        return out
    same = (old == new and type(old) is type(new)) or _same_number(old, new)
    return [] if same else [f"{path}: {old!r} != {new!r}"]


def _same_number(a: Any, b: Any) -> bool:
    numbers = (int, float)
    return isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool) and a == b


class _Absent:
    def __repr__(self) -> str:
        return "<absent>"


_ABSENT = _Absent()


def guard_diff(stored: Spec, new: Spec) -> list[str]:
    """What differs between two resolved specs in what decides the rows: every field but :data:`FREE`, the
    protocol's :data:`RUN_OPTIONS` and arms that only one of them has (arms and seeds may be added)."""

    def deciding(spec: Spec, arms: set[str]) -> dict[str, Any]:
        out = {k: v for k, v in spec.items() if k not in FREE}
        out["protocol"] = {k: v for k, v in spec["protocol"].items() if k not in RUN_OPTIONS}
        out["arms"] = {k: v for k, v in spec["arms"].items() if k in arms}
        return out

    common = set(stored["arms"]) & set(new["arms"])
    return diff(deciding(stored, common), deciding(new, common))


def merge(stored: Spec, new: Spec) -> Spec:
    """``new`` with the arms and seeds only ``stored`` has (what a folder holds after both ran into it)."""
    out = copy.deepcopy(new)
    out["arms"] = {**copy.deepcopy(stored["arms"]), **out["arms"]}
    out["seeds"] = sorted(set(stored["seeds"]) | set(new["seeds"]))
    return out


def dump(spec: Spec) -> str:
    """``spec`` as YAML, fields in order."""
    return yaml.safe_dump(spec, sort_keys=False, default_flow_style=None, width=120)


def study_of(name: str) -> tuple[str, str]:
    """``(study, part)`` of a spec name: ``paper_preset/NomadOffice-v0`` -> ``("paper_preset", "NomadOffice-v0")``,
    ``quick_preset`` -> ``("quick_preset", "")``."""
    study, _, part = name.partition("/")
    return study, part
