"""A tiny study on ``ToyNavRandom-v0`` (``tests.helpers.toy_nav``): settings files and a spec for the runner's tests."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from twodrl_zoo.hyperparams import hyperparams_path, read_entry

ENV = "ToyNavRandom-v0"
ALGOS = ("twoda2c", "a2c")


def toy_settings(folder: Path) -> Path:
    """``<algo>.yml`` files in ``folder`` that give the toy env the packaged ``NomadOffice-v0`` entries."""
    folder.mkdir(parents=True, exist_ok=True)
    for algo in ALGOS:
        entry = read_entry(hyperparams_path(algo), "NomadOffice-v0")
        (folder / f"{algo}.yml").write_text(yaml.safe_dump({ENV: entry}))
    return folder


def toy_spec(settings: Path, name: str = "toy", **changes: Any) -> dict[str, Any]:
    """A spec of 3 epochs of K=8, M=4, seeds 0 and 1, arms twoda2c and a2c at 2 envs; ``changes`` replace fields."""
    arms = {algo: {"algo": algo, "settings": str(settings), "override": {"n_envs": 2}} for algo in ALGOS}
    spec = {
        "name": name,
        "env": ENV,
        "gym_packages": ["tests.helpers.toy_nav"],
        "protocol": {"epochs": 3, "learn_episodes": 8, "test_episodes": 4},
        "seeds": [0, 1],
        "arms": arms,
        "report": "paper",
    }
    return {**spec, **changes}


def write_spec(path: Path, spec: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path
