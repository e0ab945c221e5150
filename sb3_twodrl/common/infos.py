"""The per-env info dicts of one batched step, kept as the env's arrays until a dict is asked for.

SB3 hands a ``VecEnv`` step's ``infos`` around as a list of ``n_envs`` dicts; a batched env
(``gymnasium.vector.VectorEnv``) returns one dict of arrays. Building 64 dicts per step costs more
than the step itself, and the learning path reads only columns (the punishment of every env) or the
envs whose episode ended. :class:`BatchInfos` is a ``Sequence`` of those dicts that builds env ``i``'s
on first access (then keeps it, so that changes to it are seen later, as with a list), and gives the
columns to those who ask: :meth:`BatchInfos.column` (the reward split, the navigation metrics) and
:class:`BatchInfosMixin` (SB3's episode buffers).

Measured gain: ``TwoDimA2C`` on the batched NomadOffice-v0 (64 envs) learns 1.16-1.23x as many env
steps per CPU second as with every step's infos made a list of dicts (the same parameters bit for bit;
one torch thread, alternating runs, median of 3, two runs on a loaded 2-core machine;
``scripts/bench_algo.py --pairs a2c-infos --batched``; ``docs/speed.md``).
"""

from collections.abc import Sequence
from typing import Any, overload

import numpy as np


def _python(value: Any) -> Any:
    return value.tolist() if isinstance(value, np.ndarray | np.generic) else value


class BatchInfos(Sequence[dict[str, Any]]):
    """``infos[i]`` of a batched step from ``columns`` (key -> array over envs) and their ``masks``
    (key -> bool array, where the env's dict has the key; a key without a mask is in every dict).

    Values become Python values as ``ndarray.tolist`` makes them.
    """

    def __init__(self, n_envs: int, columns: dict[str, np.ndarray], masks: dict[str, np.ndarray]) -> None:
        self.n_envs = n_envs
        self.columns = columns
        self.masks = masks
        self._dicts: list[dict[str, Any] | None] = [None] * n_envs

    def __len__(self) -> int:
        return self.n_envs

    @overload
    def __getitem__(self, index: int) -> dict[str, Any]: ...

    @overload
    def __getitem__(self, index: slice) -> list[dict[str, Any]]: ...

    def __getitem__(self, index: int | slice) -> dict[str, Any] | list[dict[str, Any]]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self.n_envs))]
        i = range(self.n_envs)[index]  # IndexError, negative indices
        info = self._dicts[i]
        if info is None:
            info = {}
            for key, values in self.columns.items():
                mask = self.masks.get(key)
                if mask is None or mask[i]:
                    info[key] = _python(values[i])
            self._dicts[i] = info
        return info

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sequence) and list(self) == list(other)

    def column(self, key: str) -> np.ndarray | None:
        """``[infos[i][key] for every i]`` as the env's array, or None unless every env's dict has ``key``
        (with the step's value: a dict changed since, e.g. by a callback, is read as it is now)."""
        values = self.columns.get(key)
        mask = self.masks.get(key)
        if values is None or (mask is not None and not mask.all()):
            return None
        for i, info in enumerate(self._dicts):
            if info is not None and (key not in info or info[key] != _python(values[i])):
                return None
        return values

    def indices_with(self, key: str) -> np.ndarray:
        """The envs whose dict has ``key`` (from the masks; dicts built since then are read)."""
        has = np.zeros(self.n_envs, dtype=bool)
        if key in self.columns:
            mask = self.masks.get(key)
            has[:] = True if mask is None else mask
        for i, info in enumerate(self._dicts):
            if info is not None:
                has[i] = key in info
        return np.flatnonzero(has)


class BatchInfosMixin:
    """SB3's ``_update_info_buffer`` reading only the envs whose dicts can add to its buffers: those
    with an ``"episode"`` (Monitor's episode end) or, at an episode end, an ``"is_success"``."""

    def _update_info_buffer(self, infos: Sequence[dict[str, Any]], dones: np.ndarray | None = None) -> None:
        if isinstance(infos, BatchInfos):
            done = np.zeros(len(infos), dtype=bool) if dones is None else np.asarray(dones, dtype=bool)
            success = infos.indices_with("is_success")
            rows = np.union1d(infos.indices_with("episode"), success[done[success]])
            infos, dones = [infos[int(i)] for i in rows], done[rows]
        super()._update_info_buffer(infos, dones)  # type: ignore[misc]
