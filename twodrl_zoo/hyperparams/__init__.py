"""The packaged hyperparameters: ``<algo>.yml`` in rl-zoo3's format, one entry per env.

:func:`load` gives an env's entry ready for the algorithm's constructor::

    from sb3_twodrl import TwoDimA2C
    from twodrl_zoo import hyperparams
    hp = hyperparams.load("twoda2c", "NomadOffice-v0")
    model = TwoDimA2C(hp.policy, make_vec_env("NomadOffice-v0", n_envs=hp.n_envs), **hp.kwargs)
    model.learn(hp.n_timesteps, callback=hp.callbacks())

The console commands and the bench find the files with :func:`hyperparams_path` and read an entry as
written with :func:`read_entry`; there is no default entry.

An env may state facts of its task (a user's own map, say): if its class (the registered entry point) has a
``task_facts(**options)`` class method returning a dict, :func:`twodrl_zoo.recipe.derive` turns them into
settings. :func:`resolve` is the one precedence: the written entry < what the task derives < what the user passes;
:func:`load` (given the env's options), the training command and the bench all resolve through it.
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from twodrl_zoo.recipe import REVISION, Derived, derive

__all__ = [
    "PACKAGED",
    "Hyperparams",
    "Resolved",
    "derived_settings",
    "env_class",
    "hyperparams_path",
    "load",
    "python_expression",
    "read_entry",
    "resolve",
    "task_facts",
]

PACKAGED = ("a2c", "ppo", "twoda2c", "twodppo")
"""The algorithms this package ships a file for."""

_SCHEDULED = ("learning_rate", "clip_range", "clip_range_vf")
_NOT_CONSTRUCTOR = ("n_envs", "n_timesteps", "policy", "normalize", "callback")
_ZOO_ONLY = ("env_wrapper", "vec_env_wrapper", "frame_stack", "monitor_kwargs", "env_kwargs", "eval_env_kwargs")


def hyperparams_path(algo: str, directory: str | os.PathLike | None = None) -> Path:
    """``<algo>.yml`` in ``directory``, by default this package's own file.

    :raises ValueError: if the file does not exist
    """
    if directory is None:
        path = resources.files(__name__).joinpath(f"{algo}.yml")
        if not isinstance(path, Path):  # installed in a zip: rl-zoo3 needs a file on disk
            raise ValueError(f"twodrl_zoo.hyperparams is not installed as files ({path})")
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


@dataclass(frozen=True)
class Hyperparams:
    """One env's entry, split as a training script uses it (what rl-zoo3's ``train`` does with it).

    ``TwoDimA2C(policy, env, **kwargs)`` on a VecEnv of ``n_envs`` envs (wrapped in
    ``VecNormalize(env, **normalize)`` when ``normalize`` is not None), then ``learn(n_timesteps,
    callback=callbacks())``.
    """

    algo: str
    env_id: str
    policy: str
    kwargs: dict[str, Any]
    """Constructor arguments: ``policy_kwargs`` evaluated, ``lin_<x>`` schedules as callables."""
    n_envs: int
    n_timesteps: int
    normalize: dict[str, Any] | None
    """``VecNormalize`` arguments (``gamma`` the algorithm's, as rl-zoo3 sets it); None: no normalisation."""
    callback: tuple[Any, ...]
    """The entry's callbacks as written: class paths, or ``{class path: kwargs}``."""
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    """Options of the training envs: the ones given to :func:`load` and those the env derived from them."""
    eval_env_kwargs: dict[str, Any] = field(default_factory=dict)
    """Options of the test envs (the env's derived test options over the ones given)."""
    note: str = ""
    """What the env derived from its options (:func:`env_settings`), empty if nothing."""

    def callbacks(self) -> list[Any]:
        """New instances of the entry's callbacks (rl-zoo3's format)."""
        made = []
        for spec in self.callback:
            name, kwargs = next(iter(spec.items())) if isinstance(spec, dict) else (spec, {})
            module, _, cls = name.rpartition(".")
            made.append(getattr(importlib.import_module(module), cls)(**kwargs))
        return made


def python_expression(text: str) -> Any:
    """A Python expression of a hyperparameter file, evaluated as rl-zoo3 does (``nn`` and ``th`` in scope)."""
    import torch as th
    from torch import nn

    return eval(text, {"nn": nn, "th": th, "torch": th})


def _schedule(key: str, value: Any) -> Any:
    if not isinstance(value, str):
        return value
    kind, _, start = value.partition("_")
    if kind not in ("lin", "linear"):
        raise ValueError(f"{key}: unknown schedule {value!r} (rl-zoo3's format: 'lin_<initial value>')")
    from stable_baselines3.common.utils import LinearSchedule

    return LinearSchedule(float(start), 0.0, 1.0)  # rl-zoo3's SimpleLinearSchedule: initial * progress_remaining


def env_class(env_id: str) -> tuple[Any, dict[str, Any]]:
    """The registered entry point of ``env_id`` (its class, or the function that makes it) and its registered kwargs.

    :raises ValueError: if ``env_id`` is not registered, or is registered without an entry point
    """
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    try:
        spec = gym.spec(env_id)
    except gym.error.Error as error:
        raise ValueError(f"env {env_id!r} is not registered: {error}") from None
    if spec.entry_point is None:
        raise ValueError(f"{env_id} is registered without an entry point")
    creator = spec.entry_point if callable(spec.entry_point) else load_env_creator(spec.entry_point)
    return creator, dict(spec.kwargs)


def task_facts(env_id: str, env_kwargs: dict[str, Any] | None = None) -> dict[str, Any] | None:
    """The facts the env ``env_id`` states of its task with the options ``env_kwargs`` (its class's
    ``task_facts(**options)``: :mod:`twodrl_zoo.recipe`), or None (no such method, or the registered defaults are
    the task: the paper's office).

    :raises ValueError: if the class returns something else than None or a dict
    """
    creator, registered = env_class(env_id)
    state = getattr(creator, "task_facts", None)
    if state is None:
        return None
    facts = state(**{**registered, **(env_kwargs or {})})
    if facts is not None and not isinstance(facts, dict):
        raise ValueError(f"{env_id}: task_facts must return None or a dict, got {facts!r}")
    return facts


def derived_settings(env_id: str, env_kwargs: dict[str, Any] | None = None, revision: int = REVISION) -> Derived | None:
    """The settings :func:`twodrl_zoo.recipe.derive` (rule ``revision``) gives the task of ``env_id`` with
    ``env_kwargs``; None where the env states no facts (:func:`task_facts`)."""
    facts = task_facts(env_id, env_kwargs)
    return None if facts is None else derive(facts, revision)


@dataclass(frozen=True)
class Resolved:
    """A run's settings, resolved once (:func:`resolve`): the rl-zoo3 entry, the training and test env options."""

    entry: dict[str, Any]
    """The entry as rl-zoo3 reads it: the written one < what the env's task derives < what the user passes."""
    env_kwargs: dict[str, Any]
    eval_env_kwargs: dict[str, Any]
    note: str = ""
    """What was derived from the task (:class:`twodrl_zoo.recipe.Derived`), empty if nothing."""


def resolve(
    entry: dict[str, Any],
    derived: Derived | None,
    hyperparams: dict[str, Any] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    eval_env_kwargs: dict[str, Any] | None = None,
) -> Resolved:
    """The one precedence of run settings: the written ``entry`` (packaged, rl-zoo3's or the user's file) < the
    settings ``derived`` from the env's task < what the user passes (``hyperparams``, ``env_kwargs``,
    ``eval_env_kwargs``). Used by the train and enjoy commands, :func:`load`, the manager and both bench protocols.

    Training envs get the entry's ``env_kwargs`` < the derived training options < ``env_kwargs`` (the user's:
    those of ``hyperparams`` < ``env_kwargs``); test envs the entry's ``env_kwargs`` < the user's < the derived test
    options (the map's start, the time limit) < ``eval_env_kwargs``.
    """
    derived = derived or Derived()
    hyperparams = dict(hyperparams or {})
    written = dict(entry.get("env_kwargs") or {})
    given = {**(hyperparams.pop("env_kwargs", None) or {}), **(env_kwargs or {})}
    merged = {**entry, **derived.hyperparams, **hyperparams}
    train = {**written, **derived.env_kwargs, **given}
    test = {**written, **given, **derived.eval_env_kwargs, **(eval_env_kwargs or {})}
    if train:
        merged["env_kwargs"] = train
    return Resolved(merged, train, test, derived.note)


def load(
    algo: str, env_id: str, directory: str | os.PathLike | None = None, env_kwargs: dict[str, Any] | None = None
) -> Hyperparams:
    """The ``env_id`` entry of ``<algo>.yml`` (the packaged file, or the one in ``directory``), ready to train.

    With ``env_kwargs`` (the env's options, e.g. ``{"map": "my_office.json"}``) the settings the env's task derives
    (:func:`derived_settings`) go over the entry's (:func:`resolve`) and fill :attr:`Hyperparams.env_kwargs` and
    :attr:`Hyperparams.eval_env_kwargs`.

    :raises ValueError: naming ``algo`` or ``env_id`` and what exists, if there is no such file or entry,
        or if the entry uses an rl-zoo3 key this function does not apply (train it with ``sb3-twodrl-train``)
    """
    if directory is None and algo not in PACKAGED:
        raise ValueError(f"algo {algo!r} has no packaged hyperparameters (packaged: {', '.join(PACKAGED)})")
    path = hyperparams_path(algo, directory)
    derived = derived_settings(env_id, env_kwargs) if env_kwargs is not None else None
    resolved = resolve(read_entry(path, env_id), derived, env_kwargs=env_kwargs)
    entry = {key: value for key, value in resolved.entry.items() if key != "env_kwargs"}
    zoo_only = [key for key in _ZOO_ONLY if key in entry]
    if zoo_only:
        raise ValueError(f"{path}, {env_id}: {', '.join(zoo_only)} is applied by rl-zoo3 only (sb3-twodrl-train)")
    kwargs = {key: value for key, value in entry.items() if key not in _NOT_CONSTRUCTOR}
    for key in _SCHEDULED:
        if key in kwargs:
            kwargs[key] = _schedule(key, kwargs[key])
    if isinstance(kwargs.get("policy_kwargs"), str):
        kwargs["policy_kwargs"] = python_expression(kwargs["policy_kwargs"])
    normalize = entry.get("normalize", False)
    if isinstance(normalize, str):
        normalize = python_expression(normalize)
    if normalize is True:
        normalize = {}
    elif normalize is False:
        normalize = None
    if normalize is not None and "gamma" in kwargs:
        normalize = {**normalize, "gamma": kwargs["gamma"]}
    callback = entry.get("callback") or []
    return Hyperparams(
        algo=algo,
        env_id=env_id,
        policy=entry.get("policy", "MlpPolicy"),
        kwargs=kwargs,
        n_envs=int(entry.get("n_envs", 1)),
        n_timesteps=int(float(entry["n_timesteps"])),
        normalize=normalize,
        callback=tuple(callback if isinstance(callback, list) else [callback]),  # one callback or a list
        env_kwargs=resolved.env_kwargs,
        eval_env_kwargs=resolved.eval_env_kwargs,
        note=resolved.note,
    )
