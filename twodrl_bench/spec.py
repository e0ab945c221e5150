"""Studies as data: a spec (a YAML file) names an env, a protocol, seeds and arms; this module loads,
validates and compares specs (the YAML layer; :mod:`twodrl_bench.experiment` resolves a spec into the study object).

A spec is packaged as ``twodrl_bench/specs/<study>.yml`` or, for a study of several parts,
``twodrl_bench/specs/<study>/<part>.yml``; its name is that path without ``.yml``. Fields
(``docs/studies.md``): ``name``, ``env``, ``env_kwargs`` ({}), ``gym_packages`` ([twodrl_envs]), ``protocol``
(the paper's epochs ``{epochs, learn_episodes, test_episodes}`` or ``{timesteps, eval_episodes}``, completed
with the defaults of :class:`~twodrl_bench.protocol.EpochProtocol` or
:class:`~twodrl_bench.protocol.TimestepsProtocol`), ``seeds``, ``arms`` (name -> ``{algo, override,
settings}``) and/or ``grid`` (points that expand into arms, kept in the spec for the report),
``rules`` (free-form, read by the report) and ``report`` (a module of :mod:`twodrl_bench.reports`, or a dotted
path; optional, default None: the runner writes the rows only).
"""

from __future__ import annotations

import copy
import itertools
import re
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

Spec = dict[str, Any]

FIELDS = ("name", "env", "env_kwargs", "gym_packages", "protocol", "seeds", "arms", "grid", "rules", "report")
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
    """The protocol mapping completed with its defaults (:func:`twodrl_bench.protocol.protocol_of`)."""
    from twodrl_bench.protocol import protocol_of

    try:
        return protocol_of(protocol).as_dict()
    except ValueError as error:
        raise ValueError(f"{source}: {error}") from None


def _arm(source: str, name: Any, arm: Any) -> dict[str, Any]:
    if not isinstance(name, str) or not _ARM_NAME.match(name):
        raise _fail(source, "arms", "names must be letters, digits and _.=+- (a file name)", name)
    arm = dict(_mapping(source, f"arms.{name}", arm))
    unknown = sorted(set(arm) - {"algo", "override", "settings"})
    if unknown:
        raise _fail(source, f"arms.{name}", "takes only algo, override and settings", unknown)
    from twodrl_bench.algorithms import ALGOS

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


def dump(spec: Spec) -> str:
    """``spec`` as YAML, fields in order."""
    return yaml.safe_dump(spec, sort_keys=False, default_flow_style=None, width=120)


def study_of(name: str) -> tuple[str, str]:
    """``(study, part)`` of a spec name: ``paper_preset/NomadOffice-v0`` -> ``("paper_preset", "NomadOffice-v0")``,
    ``quick_preset`` -> ``("quick_preset", "")``."""
    study, _, part = name.partition("/")
    return study, part
