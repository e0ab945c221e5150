"""Turn an environment's feedback into the paper's two evaluations (r_R, r_P), eq. 3-4 and 11-12.

2D-RL needs a reward evaluation ``r_R`` and a punishment evaluation ``r_P >= 0`` per step.
Gymnasium environments hand back one scalar reward and an ``info`` dict; a *reward split*
maps ``(reward, info)`` to ``(r_R, r_P)``.
"""

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

RewardSplit = Callable[[float, dict[str, Any]], tuple[float, float]]

SPLIT_MODES = ("auto", "info", "cost", "sign")


def split_info(reward: float, info: dict[str, Any]) -> tuple[float, float]:
    """The scalar reward is the net ``r_R - r_P`` and ``info["punishment"]`` holds ``r_P``."""
    punishment = float(info["punishment"])
    return reward + punishment, punishment


def split_cost(reward: float, info: dict[str, Any]) -> tuple[float, float]:
    """Safety-Gymnasium convention: ``r_R = reward``, ``r_P = info["cost"]``."""
    return reward, float(info["cost"])


def split_sign(reward: float, info: dict[str, Any]) -> tuple[float, float]:
    """Positive part of the reward is ``r_R``, negative part is ``r_P``."""
    return max(reward, 0.0), max(-reward, 0.0)


def split_auto(reward: float, info: dict[str, Any]) -> tuple[float, float]:
    """``info`` if ``info["punishment"]`` exists, else ``cost`` if ``info["cost"]`` exists, else ``sign``."""
    if "punishment" in info:
        return split_info(reward, info)
    if "cost" in info:
        return split_cost(reward, info)
    return split_sign(reward, info)


_SPLITS: dict[str, RewardSplit] = {"auto": split_auto, "info": split_info, "cost": split_cost, "sign": split_sign}


def make_reward_split(reward_split: str | RewardSplit) -> RewardSplit:
    """Resolve a ``reward_split`` argument (a mode name or a callable) to a function."""
    if callable(reward_split):
        return reward_split
    if isinstance(reward_split, str) and reward_split in _SPLITS:
        return _SPLITS[reward_split]
    raise ValueError(
        f"reward_split must be one of {SPLIT_MODES} or a callable (reward, info) -> (r_R, r_P), got {reward_split!r}"
    )


def split_rewards(
    reward_split: RewardSplit, rewards: np.ndarray, infos: Sequence[dict[str, Any]], timestep: int
) -> tuple[np.ndarray, np.ndarray]:
    """Split one vectorised step's rewards into float32 arrays ``(r_R, r_P)``.

    :raises ValueError: if a reward is not finite or a punishment is negative or not finite,
        naming the env index and the timestep where it appeared.
    """
    pairs = [reward_split(float(reward), info) for reward, info in zip(rewards, infos, strict=True)]
    reward_r, reward_p = np.array(pairs, dtype=np.float64).reshape(-1, 2).T
    bad = ~(np.isfinite(reward_r) & np.isfinite(reward_p) & (reward_p >= 0.0))
    if bad.any():
        idx = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"reward split gave (r_R, r_P) = ({reward_r[idx]}, {reward_p[idx]}) for env {idx} at timestep {timestep}: "
            "r_R must be finite and the punishment r_P finite and >= 0"
        )
    return reward_r.astype(np.float32), reward_p.astype(np.float32)
