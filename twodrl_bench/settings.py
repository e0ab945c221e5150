"""An arm's settings: which rl-zoo3 hyperparameter file it reads, which entry, and the constructor defaults it leaves
in force (what :class:`twodrl_bench.experiment.Arm` resolves an arm with)."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

from twodrl_bench.algorithms import SUFFIXES, algo_class, stock_algo
from twodrl_zoo.hyperparams import derived_settings, hyperparams_path, read_entry, resolve

ZOO_ONLY = ("n_timesteps", "callback", "normalize", "env_wrapper", "vec_env_wrapper", "frame_stack")
"""Keys of an rl-zoo3 entry that only rl-zoo3 reads: dropped from an epoch protocol's settings."""
_NOT_SETTINGS = ("policy", "env", "verbose", "seed", "device", "tensorboard_log", "_init_setup_model")


def settings_algo(algo: str) -> str:
    """The algorithm whose settings file ``algo`` reads: ``<algo>``'s for ``<algo><suffix>``
    (:data:`twodrl_bench.algorithms.SUFFIXES`)."""
    for suffix in SUFFIXES:
        algo = algo.removesuffix(suffix)
    return algo


def settings_file(algo: str, settings: str = "packaged") -> Path:
    """The rl-zoo3 hyperparameter file an arm of ``algo`` reads: ``packaged`` (:mod:`twodrl_zoo.hyperparams`),
    ``rl-zoo3`` (rl-zoo3's own, of the stock algorithm the class extends: :func:`twodrl_bench.algorithms.stock_algo`)
    or a folder of ``<algo>.yml``.

    :raises ValueError: if the file does not exist
    """
    if settings == "rl-zoo3":
        import rl_zoo3

        algo = stock_algo(algo)
        path = Path(rl_zoo3.__file__).parent / "hyperparams" / f"{algo}.yml"
        if not path.is_file():
            raise ValueError(f"settings: rl-zoo3 has no hyperparameter file for {algo!r} ({path})")
        return path
    return hyperparams_path(settings_algo(algo), None if settings == "packaged" else settings)


def epoch_entry(path: str | Path, env_id: str) -> dict[str, Any]:
    """The ``env_id`` entry of an rl-zoo3 hyperparameter file as written, without :data:`ZOO_ONLY` keys.

    :raises ValueError: if the file does not exist or has no entry for ``env_id``
    """
    return {k: v for k, v in read_entry(path, env_id).items() if k not in ZOO_ONLY}


def check_constants(hyperparams: dict[str, Any], where: str) -> None:
    """Refuse a schedule (``lin_...``): an epoch protocol has no total budget to schedule over.

    :raises ValueError: naming ``where``, the key and the value
    """
    for key, value in hyperparams.items():
        if isinstance(value, str) and value.startswith(("lin_", "linear_")):
            raise ValueError(f"{where}: {key} is a schedule ({value!r}); the epoch protocol takes constants")


def timesteps_entry(arm: dict[str, Any], env: str, protocol: dict[str, Any]) -> dict[str, Any]:
    """The rl-zoo3 entry ``arm`` trains with: its settings' entry (``protocol.entry``, else ``env``), the arm's
    ``override`` over it, and the ``Monitor`` key of ``protocol.events``.

    :raises ValueError: if the file or entry is missing, or if a 2D-RL arm that reads ``info`` would see rewards
        that ``VecNormalize`` rescales (its ``r_R = reward + info["punishment"]`` would mix two scales)
    """
    if not isinstance(arm, dict) or not isinstance(arm.get("algo"), str):
        raise ValueError(f"arm must be a mapping with an 'algo' name, got {arm!r}")
    written = read_entry(settings_file(arm["algo"], arm.get("settings", "packaged")), protocol.get("entry") or env)
    entry = resolve(written, None, arm.get("override")).entry
    if protocol.get("events"):
        entry["monitor_kwargs"] = monitor_kwargs(protocol["events"])
    check_entry(arm["algo"], entry, protocol)
    return entry


STUDY_REVISION = 1
"""The revision of the settings rule (:mod:`twodrl_zoo.recipe`) the committed studies ran with (their rows)."""


def test_env_kwargs(env: str, env_kwargs: dict[str, Any]) -> dict[str, Any]:
    """The options of a test env of ``env``: ``env_kwargs`` with the test options of its task (the map's start and
    time limit, by the rule of :data:`STUDY_REVISION`), as ``sb3-twodrl-train`` tests
    (:func:`twodrl_zoo.hyperparams.resolve`)."""
    derived = derived_settings(env, env_kwargs, revision=STUDY_REVISION)
    return resolve({}, derived, env_kwargs=env_kwargs).eval_env_kwargs


def monitor_kwargs(events: str) -> str:
    """The entry's ``monitor_kwargs`` that make the training envs' ``Monitor`` record the ``events`` info key."""
    return f"dict(info_keywords=('{events}',))"


def check_entry(name: str, entry: dict[str, Any], protocol: dict[str, Any]) -> None:
    """:raises ValueError: if the ``Monitor`` does not record ``protocol.events``, or if a 2D-RL arm that reads
    ``info`` would see rewards that ``VecNormalize`` rescales (its ``r_R = reward + info["punishment"]`` would mix
    two scales)"""
    events = protocol.get("events")
    if events and entry.get("monitor_kwargs") != monitor_kwargs(events):
        raise ValueError(f"arm {name!r}: monitor_kwargs must record {events!r} (resolve the arm with resolve_arm)")
    normalize = entry.get("normalize", False)
    scaled = normalize if isinstance(normalize, bool) else "'norm_reward': False" not in normalize
    if scaled and entry.get("reward_split") in ("info", "cost"):
        raise ValueError(f"arm {name!r}: the entry normalises rewards, which reward_split='info' cannot split")


def constructor_defaults(cls: type) -> dict[str, Any]:
    """The default of every constructor argument of ``cls``: its ``__init__``'s, then, while an ``__init__`` passes
    ``**kwargs`` on, those of the next class of the MRO that defines one (a subclass's default wins)."""
    out: dict[str, Any] = {}
    for klass in cls.__mro__:
        if "__init__" not in vars(klass) or klass is object:
            continue
        parameters = inspect.signature(vars(klass)["__init__"]).parameters.values()
        for p in parameters:
            if p.default is not p.empty:
                out.setdefault(p.name, p.default)
        if not any(p.kind is p.VAR_KEYWORD for p in parameters):
            break
    return out


def class_defaults(algo: str, hyperparams: dict[str, Any]) -> dict[str, str]:
    """The constructor defaults of ``algo``'s class (:func:`constructor_defaults`) that ``hyperparams`` leave in
    force, as ``repr``: a run resumed after a default changed (a new release) is then refused, not mixed."""
    defaults = constructor_defaults(algo_class(algo))
    return {
        name: repr(value) for name, value in defaults.items() if name not in _NOT_SETTINGS and name not in hyperparams
    }
