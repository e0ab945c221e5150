"""Turn an environment's feedback into the paper's two evaluations (r_R, r_P), eq. 3-4 and 11-12.

2D-RL needs a reward evaluation ``r_R`` and a punishment evaluation ``r_P >= 0`` per step.
Gymnasium environments hand back one scalar reward and an ``info`` dict; a *reward split*
maps them to ``(r_R, r_P)``. The named modes work on a whole vectorised step at once; a user's
callable maps one env's ``(reward, info)``.
"""

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

RewardSplit = Callable[[float, dict[str, Any]], tuple[float, float]]
BatchSplit = Callable[[np.ndarray, Sequence[dict[str, Any]]], tuple[np.ndarray, np.ndarray]]

SPLIT_MODES = ("auto", "info", "cost", "sign", "none")


def _info_values(infos: Sequence[dict[str, Any]], key: str, mode: str) -> np.ndarray:
    """``info[key]`` of every env as float64.

    :raises ValueError: naming the mode, the key and the env if one is missing, or if a value is not
        a real scalar (a string, even ``"0"``, None or a bool is an error, not a number)
    """
    try:
        values = np.array([info[key] for info in infos])
    except KeyError:
        idx = next(i for i, info in enumerate(infos) if key not in info)
        raise ValueError(
            f'reward_split="{mode}" needs info["{key}"] at every step, but env {idx}\'s info has only the keys '
            f'{sorted(infos[idx])} (use another reward_split, e.g. "sign" or a callable)'
        ) from None
    except ValueError:  # ragged sequences
        values = np.empty(0)
    if values.dtype.kind not in "iuf" or values.shape != (len(infos),):
        bad = [info[key] for info in infos]
        raise ValueError(f'reward_split="{mode}": info["{key}"] must be a real number in every env, got {bad!r}')
    return values.astype(np.float64, copy=False)


def split_info(rewards: np.ndarray, infos: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """The scalar reward is the net ``r_R - r_P`` and ``info["punishment"]`` holds ``r_P``."""
    punishments = _info_values(infos, "punishment", "info")
    return rewards + punishments, punishments


def split_cost(rewards: np.ndarray, infos: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """Safety-Gymnasium convention: ``r_R = reward``, ``r_P = info["cost"]``."""
    return rewards, _info_values(infos, "cost", "cost")


def split_sign(rewards: np.ndarray, infos: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """The positive part of the reward is ``r_R``, the negative part ``r_P`` (``r_R - r`` is exactly that)."""
    reward_r = np.maximum(rewards, 0.0)
    return reward_r, reward_r - rewards


def split_none(rewards: np.ndarray, infos: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """One stream: ``r_R`` is the whole reward, ``r_P = 0`` (with ``punishment_weight=0``, A2C's signal)."""
    return rewards, np.zeros_like(rewards)


def split_auto(rewards: np.ndarray, infos: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """Per env: ``info`` if ``info["punishment"]`` exists, else ``cost`` if ``info["cost"]`` exists, else ``sign``."""
    keyed = ["punishment" in info or "cost" in info for info in infos]
    if not any(keyed):
        return split_sign(rewards, infos)
    if all("punishment" in info for info in infos):
        return split_info(rewards, infos)
    reward_r, reward_p = split_sign(rewards, infos)
    for idx in np.flatnonzero(keyed).tolist():
        split = split_info if "punishment" in infos[idx] else split_cost
        (reward_r[idx],), (reward_p[idx],) = split(rewards[idx : idx + 1], [infos[idx]])
    return reward_r, reward_p


_SPLITS: dict[str, BatchSplit] = {
    "auto": split_auto,
    "info": split_info,
    "cost": split_cost,
    "sign": split_sign,
    "none": split_none,
}


def make_reward_split(reward_split: str | RewardSplit) -> BatchSplit:
    """Resolve a ``reward_split`` argument (a mode name or a per-env callable) to a batch function."""
    if isinstance(reward_split, str) and reward_split in _SPLITS:
        return _SPLITS[reward_split]
    if callable(reward_split):

        def split_each(rewards: np.ndarray, infos: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
            pairs = [reward_split(float(r), info) for r, info in zip(rewards, infos, strict=True)]
            try:
                split = np.array(pairs, dtype=np.float64)
            except (TypeError, ValueError):
                split = np.empty(0)
            if split.shape != (len(infos), 2):
                raise ValueError(f"reward_split callable must return a pair of real numbers (r_R, r_P), got {pairs!r}")
            return split[:, 0], split[:, 1]

        return split_each
    raise ValueError(
        f"reward_split must be one of {SPLIT_MODES} or a callable (reward, info) -> (r_R, r_P), got {reward_split!r}"
    )


PYTHON_CHECK_MAX_ENVS = 128


def _valid(reward_r: np.ndarray, reward_p: np.ndarray) -> np.ndarray:
    """Per env: ``r_R`` finite and ``r_P`` finite and >= 0."""
    return np.isfinite(reward_r) & np.isfinite(reward_p) & (reward_p >= 0.0)


def _all_valid(reward_r: np.ndarray, reward_p: np.ndarray) -> bool:
    """Whether every ``r_R`` is finite and every ``r_P`` finite and >= 0.

    Inside the training loop a numpy reduction costs tens of times what it costs alone, so up to
    ``PYTHON_CHECK_MAX_ENVS`` envs the check runs on Python floats (a NaN or an infinity makes the
    float64 sum non-finite, a negative ``r_P`` the min); beyond, where a Python float per env
    costs more, on numpy with ``count_nonzero`` (not a reduction ufunc, so cheap).
    """
    if reward_p.size <= PYTHON_CHECK_MAX_ENVS:
        punishments = reward_p.tolist()
        return min(punishments) >= 0.0 and math.isfinite(sum(reward_r.tolist()) + sum(punishments))
    return np.count_nonzero(_valid(reward_r, reward_p)) == reward_p.size


def split_rewards(
    reward_split: BatchSplit, rewards: np.ndarray, infos: Sequence[dict[str, Any]], timestep: int
) -> tuple[np.ndarray, np.ndarray]:
    """Split one vectorised step's rewards into float32 arrays ``(r_R, r_P)``.

    :raises ValueError: if the split cannot be made (a missing ``info`` key, a value that is not a
        number), or if a reward is not finite or a punishment is negative or not finite (after
        the cast to the buffer's float32: a finite 1e300 is an error, not a silent infinity),
        naming the env index and the timestep where it appeared.
    """
    try:
        reward_r, reward_p = reward_split(rewards.astype(np.float32, copy=False), infos)
    except ValueError as error:
        raise ValueError(f"{error} (at timestep {timestep})") from error
    reward_r, reward_p = reward_r.astype(np.float32, copy=False), reward_p.astype(np.float32, copy=False)
    if not _all_valid(reward_r, reward_p):
        idx = int(np.flatnonzero(~_valid(reward_r, reward_p))[0])
        raise ValueError(
            f"reward split gave (r_R, r_P) = ({reward_r[idx]}, {reward_p[idx]}) for env {idx} at timestep {timestep}: "
            "r_R must be finite and the punishment r_P finite and >= 0 (in float32)"
        )
    return reward_r, reward_p
