"""N stand-in robots (``NomadOfficeReal-v0``) stepped in one numpy call.

:class:`BatchedNomadOfficeReal` is :class:`~twodrl_envs.nomad.batched.BatchedNomadOffice` with the
realistic model of :mod:`twodrl_envs.nomad.realistic`: continuous true poses, dead-reckoned odometry,
readings of :meth:`~twodrl_envs.nomad.realistic.Scene.ranges`. All per-step randomness is counter-based,
so sub-env ``i`` reset with seed ``s`` equals ``gym.make("twodrl_envs:NomadOfficeReal-v0")`` reset with
seed ``s`` and reset again after every episode.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.nomad.batched import BatchedNomadOffice, SB3VecEnvAdapter, make_sb3_vec_env
from twodrl_envs.nomad.office import check_observation
from twodrl_envs.nomad.realistic import RealisticModel


class BatchedNomadOfficeReal(BatchedNomadOffice):
    """``num_envs`` stand-in robots: ``info["position_cm"]`` is the true pose, the odometry is dead reckoning."""

    def __init__(
        self,
        num_envs: int,
        map: str | Path | None = None,
        *,
        model: RealisticModel | None = None,
        observe_odometry: bool = True,
        render_mode: str | None = None,
        max_episode_steps: int = MAX_EPISODE_STEPS,
        observation: str = "sensors",
    ) -> None:
        check_observation(observation, False, type(self).__name__)
        if model is not None and not isinstance(model, RealisticModel):
            raise TypeError(f"model must be a RealisticModel or None, got {type(model).__name__}: {model!r}")
        super().__init__(
            num_envs,
            map,
            observe_odometry=observe_odometry,
            render_mode=render_mode,
            max_episode_steps=max_episode_steps,
        )
        self.model = RealisticModel() if model is None else model
        self.scene = self.model.scene(self.core.office)
        self._lattice = False

    def _pose_readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        return self.scene.readings(positions, keys, steps)

    def _displacement(self, actions: np.ndarray) -> np.ndarray:
        return self.model.displacement(actions, self._key, self._t)


def make_real_vec_env(n_envs: int, seed: int | None = None, **kwargs: Any) -> SB3VecEnvAdapter:
    """An SB3 ``VecEnv`` of ``n_envs`` batched ``NomadOfficeReal-v0`` robots."""
    return make_sb3_vec_env(n_envs, seed, batch_class=BatchedNomadOfficeReal, **kwargs)
