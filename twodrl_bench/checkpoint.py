"""Checkpoints of a learning run: the whole algorithm, its VecEnv and every random generator, in one file.

SB3's ``save`` keeps what ``predict`` and a new ``learn`` need and drops on purpose what a run carries
between rollouts (TwoDimA2C drops the interest of the last transition, whose identity with
``_last_obs`` says it is still valid). A checkpoint instead pickles the algorithm object's whole
``__dict__`` (policy with its optimizer and buffers such as the running interest, rollout state,
counters), its VecEnv (so the envs' positions, episode counters and generators) and the torch,
numpy and Python generators in one pickle, which keeps the identities between them; only the logger
(open TensorBoard files) is left out, and ``learn(reset_num_timesteps=False)`` opens it again. A
checkpoint is therefore tied to the package versions that wrote it; final models are saved with
``save`` as well.
"""

from __future__ import annotations

import os
import random
from pathlib import Path
from typing import Any

import cloudpickle
import numpy as np
import torch as th
from stable_baselines3.common.base_class import BaseAlgorithm

FORMAT = 1
_NOT_PICKLED = ("_logger",)


def rng_state() -> dict[str, Any]:
    return {"torch": th.get_rng_state(), "numpy": np.random.get_state(), "random": random.getstate()}


def set_rng_state(state: dict[str, Any]) -> None:
    th.set_rng_state(state["torch"])
    np.random.set_state(state["numpy"])
    random.setstate(state["random"])


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to a temporary file beside ``path``, flush it to disk, then rename it over ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with tmp.open("wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def save_checkpoint(path: str | Path, model: BaseAlgorithm, extra: dict[str, Any]) -> None:
    """Atomically write ``model`` (with its env), the global generators and ``extra`` (the runner's state)."""
    algo = {k: v for k, v in vars(model).items() if k not in _NOT_PICKLED}
    payload = {"format": FORMAT, "class": type(model), "algo": algo, "rng": rng_state(), "extra": extra}
    atomic_write_bytes(Path(path), cloudpickle.dumps(payload))


def load_checkpoint(path: str | Path) -> tuple[BaseAlgorithm, dict[str, Any], dict[str, Any]]:
    """The algorithm (env attached, logger to be configured by ``learn``), the generator states and ``extra``.

    The generator states are returned, not set: the caller sets them right before learning resumes.
    """
    with Path(path).open("rb") as f:
        payload = cloudpickle.load(f)
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ValueError(f"{path} is not a checkpoint of format {FORMAT}")
    cls = payload["class"]
    model = cls.__new__(cls)
    vars(model).update(payload["algo"])
    model._custom_logger = False  # the logger was not pickled: learn() configures a new one
    return model, payload["rng"], payload["extra"]
