"""The protocol's hyperparameters, shipped with the package: ``<algo>.yml`` in rl-zoo3's format, one entry per env.

Every reader (the console commands, ``scripts/train.py``, the tests) finds them with :func:`hyperparams_path`
and reads an env's entry with :func:`read_entry`; there is no default entry.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

PACKAGED = ("a2c", "ppo", "twoda2c", "twodppo")
"""The algorithms this package ships a file for."""


def hyperparams_path(algo: str, directory: str | os.PathLike | None = None) -> Path:
    """``<algo>.yml`` in ``directory``, by default this package's own file.

    :raises ValueError: if the file does not exist
    """
    if directory is None:
        path = resources.files(__name__).joinpath(f"{algo}.yml")
        if not isinstance(path, Path):  # installed in a zip: rl-zoo3 needs a file on disk
            raise ValueError(f"sb3_twodrl.hyperparams is not installed as files ({path})")
    else:
        path = Path(directory) / f"{algo}.yml"
    if not path.is_file():
        raise ValueError(f"hyperparameter file {str(path)!r} does not exist")
    return path


def read_entry(path: str | os.PathLike, env_id: str) -> dict[str, Any]:
    """The ``env_id`` entry of the rl-zoo3 hyperparameter file ``path``, as written.

    :raises ValueError: if the file does not exist or has no entry for ``env_id``
    """
    if not Path(path).is_file():
        raise ValueError(f"hyperparameter file {str(path)!r} does not exist")
    conf = yaml.safe_load(Path(path).read_text()) or {}
    if env_id not in conf:
        raise ValueError(f"{path} has no entry for {env_id!r} (its entries: {', '.join(conf)})")
    return dict(conf[env_id])
