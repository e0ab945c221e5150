"""Where a map comes from: a map file, a shipped map's name, or a generated office (``"generated:SIZE:SEED"``).

:func:`load_map` resolves a map source (:func:`map_source`), reads its JSON object (:func:`map_data`: the file's,
or :func:`~twodrl_envs.nomad.generator.generate_map`'s) and checks it (:func:`~twodrl_envs.nomad.geometry.parse_map`).
It stands above both the geometry and the generator, which builds its offices with the geometry.
"""

from __future__ import annotations

import json
from pathlib import Path

from twodrl_envs.nomad.generator import generate_map, parse_generated
from twodrl_envs.nomad.geometry import (
    _MAP_CHOICES,
    GENERATED_PREFIX,
    MAPS_DIR,
    SHIPPED_MAPS,
    OfficeMap,
    default_map_path,
    is_generated,
    parse_map,
)


def map_source(path: str | Path | None = None) -> str:
    """The resolved path of a map file; ``None`` is the shipped office, a name in ``SHIPPED_MAPS`` a shipped map.

    ``"generated:SEED"`` and ``"generated:SIZE:SEED"`` resolve to the canonical ``generated:SIZE:SEED``.
    """
    if path is not None and not isinstance(path, str | Path):
        raise TypeError(f"map must be a path (str or pathlib.Path) or None, got {type(path).__name__}: {path!r}")
    if path is None:
        path = default_map_path()
    elif isinstance(path, str) and path in SHIPPED_MAPS:
        path = MAPS_DIR / f"{path}.json"
    elif isinstance(path, str) and is_generated(path):
        size, seed = parse_generated(path)
        return f"{GENERATED_PREFIX}{size}:{seed}"
    elif str(path).strip() == "":
        raise ValueError(f"map must be {_MAP_CHOICES}, got {path!r}")
    return str(Path(path).resolve())


def map_data(source: str) -> dict:
    """The JSON object of a resolved map source (:func:`map_source`): the file's, or the generated office's."""
    if is_generated(source):
        size, seed = parse_generated(source)
        return generate_map(seed, size)
    if not Path(source).is_file():
        what = "is a directory" if Path(source).is_dir() else "does not exist"
        raise ValueError(f"map file {source} {what} (map must be {_MAP_CHOICES})")
    try:
        data = json.loads(Path(source).read_text())
    except json.JSONDecodeError as err:
        raise ValueError(f"map file {source} is not valid JSON: {err}") from err
    if not isinstance(data, dict):
        raise ValueError(f"map file {source}: top level must be an object, got {type(data).__name__}")
    return data


def load_map(path: str | Path | None = None) -> OfficeMap:
    """Read and validate a map file (format documented in ``docs/nomad.md``); ``None`` loads the office,
    ``"office"`` / ``"open"`` a shipped map by name, ``"generated:SIZE:SEED"`` a generated office.

    Raises ``ValueError`` naming the file and the offending entry.
    """
    source = map_source(path)
    return parse_map(map_data(source), source)
