"""The timesteps job: one (arm, seed) trained with rl-zoo3 itself, then a final deterministic evaluation.

:func:`run_job` is the job function of a spec whose protocol is ``{timesteps, eval_episodes}``. The arm trains
with ``rl_zoo3.train`` at its settings' entry; the training envs' ``Monitor`` records every training episode's
return and punishment events, from which come the learning curve and the training event rates; the final model
then runs ``eval_episodes`` deterministic episodes on a fresh env seeded ``EVAL_SEED + seed``, apart from
training (with the run's ``VecNormalize`` statistics, frozen, where the entry normalises).

Keys this job reads, beside the fields every spec has:

- ``protocol.timesteps``: the training budget (rl-zoo3's ``--n-timesteps``); ``null``: the entry's ``n_timesteps``.
- ``protocol.eval_episodes``: the final evaluation's deterministic episodes.
- ``protocol.events`` (optional): the ``info`` key holding the episode's punishment events so far; the training
  envs' ``Monitor`` records it (``monitor_kwargs``) and the evaluation reads it at each episode's end.
- ``protocol.entry`` (optional): the name of the settings entry both arms read (default: the spec's ``env``),
  e.g. rl-zoo3's ``CartPole-v1`` entry for ``CliffWalkingSplit-v1``, which has none of its own.
- ``protocol.task`` (optional): the rows' ``task`` label (default: the spec's ``env``).
- ``arms.<name>.settings``: ``packaged`` (default: :mod:`sb3_twodrl.hyperparams`' ``<algo>.yml``), ``rl-zoo3``
  (rl-zoo3's own ``hyperparams/<algo>.yml``, of the stock algorithm for a 2D-RL one: :data:`STOCK`) or a folder
  of ``<algo>.yml``; ``arms.<name>.override``: settings over the entry (the 2D-RL arguments, a budget, ...).

Resolving a spec's timesteps arm is :func:`resolve_arm`; the job gets the arm as the runner passes it, ``{name,
algo, hyperparams}`` (``name`` the rows' ``arm`` label, ``hyperparams`` :func:`resolve_arm`'s entry).

Requires the ``zoo`` extra.
"""

from __future__ import annotations

import copy
import csv
import importlib
import json
import math
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np

Row = dict[str, Any]
STOCK = {"twoda2c": "a2c", "twodppo": "ppo"}
"""The stock algorithm of each 2D-RL algorithm: whose rl-zoo3 entry it reads (a ``<algo>_auto`` arm: its
``<algo>``'s, :func:`twodrl_bench.protocol.settings_algo`)."""
EVAL_SEED = 10**6
"""Seed of the evaluation env, plus the training seed: apart from the training seeds."""
CURVE_BINS = 20
"""Learning-curve points: training episodes binned by the timestep at which they ended."""
PROTOCOL_KEYS = ("timesteps", "eval_episodes", "events", "entry", "task")


def check_protocol(protocol: dict[str, Any]) -> None:
    """:raises ValueError: naming the key, for an unknown key or a bad budget, episode count or label"""
    unknown = sorted(set(protocol) - set(PROTOCOL_KEYS))
    if unknown:
        raise ValueError(f"protocol: the timesteps protocol takes only {list(PROTOCOL_KEYS)}, got {unknown}")
    timesteps = protocol.get("timesteps")
    if timesteps is not None and (not isinstance(timesteps, int) or isinstance(timesteps, bool) or timesteps < 1):
        raise ValueError(f"protocol.timesteps must be an int >= 1 or null, got {timesteps!r}")
    episodes = protocol.get("eval_episodes")
    if not isinstance(episodes, int) or isinstance(episodes, bool) or episodes < 1:
        raise ValueError(f"protocol.eval_episodes must be an int >= 1, got {episodes!r}")
    for key in ("events", "entry", "task"):
        if protocol.get(key) is not None and not isinstance(protocol[key], str):
            raise ValueError(f"protocol.{key} must be a string or null, got {protocol[key]!r}")


def settings_file(arm: dict[str, Any]) -> Path:
    """The rl-zoo3 hyperparameter file ``arm`` reads (see the module docstring: ``settings``).

    :raises ValueError: if the file does not exist
    """
    from sb3_twodrl.hyperparams import hyperparams_path
    from twodrl_bench.protocol import settings_algo

    settings, algo = arm.get("settings", "packaged"), settings_algo(arm["algo"])
    if settings == "rl-zoo3":
        import rl_zoo3

        algo = STOCK.get(algo, algo)
        path = Path(rl_zoo3.__file__).parent / "hyperparams" / f"{algo}.yml"
        if not path.is_file():
            raise ValueError(f"settings: rl-zoo3 has no hyperparameter file for {algo!r} ({path})")
        return path
    return hyperparams_path(algo, None if settings == "packaged" else settings)


def resolve_arm(arm: dict[str, Any], env: str, protocol: dict[str, Any]) -> dict[str, Any]:
    """The rl-zoo3 entry ``arm`` trains with: its settings' entry (``protocol.entry``, else ``env``), the arm's
    ``override`` over it, and the ``Monitor`` key of ``protocol.events``.

    :raises ValueError: if the file or entry is missing, or if a 2D-RL arm that reads ``info`` would see rewards
        that ``VecNormalize`` rescales (its ``r_R = reward + info["punishment"]`` would mix two scales)
    """
    from sb3_twodrl.hyperparams import read_entry

    if not isinstance(arm, dict) or not isinstance(arm.get("algo"), str):
        raise ValueError(f"arm must be a mapping with an 'algo' name, got {arm!r}")
    entry = {**read_entry(settings_file(arm), protocol.get("entry") or env), **(arm.get("override") or {})}
    if protocol.get("events"):
        entry["monitor_kwargs"] = monitor_kwargs(protocol["events"])
    check_entry(arm["algo"], entry, protocol)
    return entry


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


def training_episodes(run_dir: Path, n_envs: int, events: str | None) -> np.ndarray:
    """Every training episode as ``(timestep it ended at, return, punishment events)``, sorted by timestep.

    The Monitor of sub-env ``i`` writes ``<run_dir>/<i>.monitor.csv``; the sub-envs step together,
    so an episode that ends at a sub-env's k-th step ends at timestep ``k * n_envs``.
    """
    rows = []
    for i in range(n_envs):
        with (run_dir / f"{i}.monitor.csv").open() as f:
            next(f)  # the JSON header
            steps = 0
            for record in csv.DictReader(f):
                steps += int(record["l"])
                rows.append((steps * n_envs, float(record["r"]), float(record[events]) if events else 0.0))
    return np.array(sorted(rows), dtype=np.float64).reshape(-1, 3)


def learning_curve(episodes: np.ndarray, n_timesteps: int, bins: int = CURVE_BINS) -> list[list[float]]:
    """Per bin of ``n_timesteps / bins`` steps: ``[end timestep, mean return, events per episode]`` (NaN if empty)."""
    edges = np.linspace(0, n_timesteps, bins + 1)
    index = np.clip(np.searchsorted(edges, episodes[:, 0], side="left") - 1, 0, bins - 1)
    curve = []
    for b in range(bins):
        inside = episodes[index == b]
        mean = inside.mean(axis=0) if len(inside) else np.full(3, math.nan)
        curve.append([float(edges[b + 1]), float(mean[1]), float(mean[2])])
    return curve


def evaluate(model: Any, env: Any, episodes: int, events: str | None) -> dict[str, float]:
    """Mean return, length and punishment events of ``episodes`` deterministic episodes, and the share with an event."""
    results: list[tuple[float, int, float]] = []
    obs = env.reset()
    total, length = 0.0, 0
    while len(results) < episodes:
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, done, info = env.step(action)
        total, length = total + float(reward[0]), length + 1
        if done[0]:
            results.append((total, length, float(info[0].get(events, 0.0)) if events else 0.0))
            total, length = 0.0, 0
    r, n, e = (np.array(x) for x in zip(*results, strict=True))
    return {
        "final_return": float(r.mean()),
        "final_return_std": float(r.std()),
        "final_length": float(n.mean()),
        "final_events": float(e.mean()),
        "final_event_share": float(np.mean(e > 0)),
    }


def run_job(
    arm: dict[str, Any],
    env: str,
    env_kwargs: dict[str, Any],
    protocol: dict[str, Any],
    seed: int,
    out_dir: str,
    gym_packages: list[str],
) -> list[Row]:
    """Train ``arm`` on ``env`` with rl-zoo3 (seed ``seed``, its logs in ``<out_dir>/zoo/<arm>_seed<seed>``, where
    an interrupted attempt's are removed first) and evaluate the final model; its one row.

    The row: ``task``, ``env``, ``arm``, ``seed``, ``n_timesteps``; the final evaluation's ``final_return`` (mean),
    ``final_return_std``, ``final_length``, ``final_events`` (per episode), ``final_event_share``; over the
    training episodes ``train_episodes``, ``train_return``, ``train_events_per_episode``, ``train_event_share``;
    ``curve`` (:func:`learning_curve` as JSON text, so that the row is flat); for an arm whose entropy coefficient
    is learned (:mod:`twodrl_bench.auto_entropy`), ``ent_coef_course`` (the final model's, as JSON text); ``wall_s``.
    """
    import torch as th
    import yaml
    from rl_zoo3 import utils as zoo_utils
    from rl_zoo3.train import train
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    from sb3_twodrl.zoo import register_zoo, run_zoo_entry
    from twodrl_bench.auto_entropy import AUTO_ENTROPY_ALGOS

    clock = time.perf_counter()
    check_protocol(protocol)
    if not isinstance(arm.get("name"), str) or not arm["name"] or not isinstance(arm.get("hyperparams"), dict):
        raise ValueError(f"arm must be {{name, algo, hyperparams}} (resolve_arm's entry), got {arm!r}")
    register_zoo()
    zoo_utils.ALGOS.update(AUTO_ENTROPY_ALGOS)  # the bench's own baselines, beside the library's algorithms
    if arm.get("algo") not in zoo_utils.ALGOS:
        raise ValueError(f"arm algo must be one of rl-zoo3's {sorted(zoo_utils.ALGOS)}, got {arm.get('algo')!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    for package in gym_packages:
        importlib.import_module(package)
    th.set_num_threads(1)
    algo, name, events = arm["algo"], arm["name"], protocol.get("events")
    entry = copy.deepcopy(arm["hyperparams"])
    check_entry(name, entry, protocol)
    if env_kwargs:
        entry["env_kwargs"] = {**(entry.get("env_kwargs") or {}), **env_kwargs}
    log = Path(out_dir) / "zoo" / f"{name}_seed{seed}"
    shutil.rmtree(log, ignore_errors=True)  # what an interrupted attempt left
    log.mkdir(parents=True)
    conf = log / f"{algo}.yml"
    conf.write_text(yaml.safe_dump({env: entry}))
    argv = ["--algo", algo, "--env", env, "--seed", str(seed), "-f", str(log), "--eval-freq", "-1"]
    argv += ["--vec-env", "dummy", "--log-interval", "-1", "--device", "cpu", "--conf-file", str(conf)]
    if protocol.get("timesteps") is not None:
        argv += ["--n-timesteps", str(protocol["timesteps"])]
    run_zoo_entry("train.py", argv, train)  # the env packages: gym_packages only (no entry-point group)
    (run,) = sorted((log / algo).glob(f"{env}_*"))
    budget = int(protocol.get("timesteps") or entry["n_timesteps"])
    train_eps = training_episodes(run, int(entry.get("n_envs", 1)), events)
    model = zoo_utils.ALGOS[algo].load(run / f"{env}.zip", device="cpu")
    eval_env = make_vec_env(
        env,
        n_envs=1,
        seed=EVAL_SEED + seed,
        wrapper_class=zoo_utils.get_wrapper_class(entry),
        env_kwargs=entry.get("env_kwargs"),
    )
    stats = run / env / "vecnormalize.pkl"
    if stats.exists():
        eval_env = VecNormalize.load(str(stats), eval_env)
        eval_env.training, eval_env.norm_reward = False, False
    final = evaluate(model, eval_env, protocol["eval_episodes"], events)
    eval_env.close()
    found = len(train_eps) > 0
    learned_coefficient = getattr(model, "ent_coef_auto", False)
    course = {"ent_coef_course": json.dumps(model.ent_coef_course)} if learned_coefficient else {}
    return [
        {
            "task": protocol.get("task") or env,
            "env": env,
            "arm": name,
            "seed": seed,
            "n_timesteps": budget,
            **final,
            "train_episodes": len(train_eps),
            "train_return": float(train_eps[:, 1].mean()) if found else math.nan,
            "train_events_per_episode": float(train_eps[:, 2].mean()) if found else math.nan,
            "train_event_share": float(np.mean(train_eps[:, 2] > 0)) if found else math.nan,
            "curve": json.dumps(learning_curve(train_eps, budget)),
            **course,
            "wall_s": round(time.perf_counter() - clock, 1),
        }
    ]
