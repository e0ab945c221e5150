"""N stand-in robots (``NomadOfficeReal-v0``) stepped in one numpy call.

:class:`BatchedNomadOfficeReal` is :class:`~envs.nomad.batched.BatchedNomadOffice` with the
realistic model of :mod:`envs.nomad.realistic`: continuous true poses, dead-reckoned odometry,
readings of :meth:`~envs.nomad.realistic.Scene.ranges`. All per-step randomness is counter-based,
so sub-env ``i`` reset with seed ``s`` equals ``gym.make("envs:NomadOfficeReal-v0")`` reset with
seed ``s`` and reset again after every episode.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from envs import MAX_EPISODE_STEPS
from envs.nomad import sensors
from envs.nomad.batched import BatchedNomadOffice, SB3VecEnvAdapter, make_sb3_vec_env
from envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, swept_clearance
from envs.nomad.office import COLLISION_PUNISHMENT, MOVE_PUNISHMENT, check_observation, episode_keys, route_code_at
from envs.nomad.realistic import RealisticModel


class BatchedNomadOfficeReal(BatchedNomadOffice):
    """``num_envs`` stand-in robots: ``info["position_cm"]`` is the true pose, the odometry is dead reckoning."""

    def __init__(
        self,
        num_envs: int,
        map: str | Path | None = None,
        *,
        model: RealisticModel | None = None,
        observe_odometry: bool = True,
        max_episode_steps: int = MAX_EPISODE_STEPS,
        observation: str = "sensors",
    ) -> None:
        check_observation(observation, False, type(self).__name__)
        if model is not None and not isinstance(model, RealisticModel):
            raise TypeError(f"model must be a RealisticModel or None, got {type(model).__name__}: {model!r}")
        super().__init__(num_envs, map, observe_odometry=observe_odometry, max_episode_steps=max_episode_steps)
        self.model = RealisticModel() if model is None else model
        self.scene = self.model.scene(self.core.office)
        self._start = np.array(self.core.office.start, dtype=np.float64)
        self._start_route = int(route_code_at(self.core.office, self._start))
        self._pos = np.repeat(self._start[None], self.num_envs, axis=0)
        self._odo = self._pos.copy()

    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every robot to the start; ``seed=s`` seeds sub-env ``i`` with ``s + i``."""
        self._pos[:] = self._start
        self._odo[:] = self._start
        obs, info = super().reset(seed=seed, options=options)
        self._route[:] = self._start_route
        return obs, info

    def _observe(self, rows: np.ndarray) -> np.ndarray:
        readings = self.scene.readings(self._pos[rows], self._key[rows], self._t[rows])
        if not self.single_observation_space.shape[0] > sensors.N_READINGS:
            return readings
        return np.concatenate([readings, self.core.odometry(self._odo[rows])], axis=1)

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Move every robot (eq. 11-12 evaluations); finished robots restart in the same call."""
        actions = np.asarray(actions)
        if actions.shape != (self.num_envs,) or not np.all((actions >= 0) & (actions < 4)):
            raise ValueError(f"actions must be {self.num_envs} integers in 0..3, got {actions!r}")
        actions = actions.astype(np.intp)
        self._t += 1
        office = self.core.office
        target = self._pos + self.model.displacement(actions, self._key, self._t)
        clear = swept_clearance(self._pos, target, office.walls) > ROBOT_RADIUS_CM
        collided = ~(clear & office.inside_bounds(target))
        moved = ~collided
        self._pos[moved] = target[moved]
        self._odo[moved] += MOVES_CM[actions[moved]]
        code = route_code_at(office, self._pos)
        self._route = np.where(moved & (code > 0), code, self._route).astype(np.int8)
        goal = office.in_region("goal", self._pos) & moved
        rewards = self._step_reward[np.where(collided, 2, goal.astype(np.intp))]
        terminated = collided | goal
        truncated = (self._t >= self.max_episode_steps) & ~terminated
        obs = self._observe(self._all)
        info = self._info(np.where(collided, COLLISION_PUNISHMENT, MOVE_PUNISHMENT), collided, goal)
        done = terminated | truncated
        if done.any():
            info["final_obs"], info["_final_obs"] = obs.copy(), done
            self._episode[done] += 1
            self._key[done] = episode_keys(self._base[done], self._episode[done])
            self._pos[done] = self._start
            self._odo[done] = self._start
            self._route[done] = self._start_route
            self._t[done] = 0
            obs[done] = self._observe(done)
        return obs, rewards, terminated, truncated, info

    def _info(self, punishment: np.ndarray, collided: np.ndarray, goal: np.ndarray) -> dict[str, Any]:
        info = super()._info(punishment, collided, goal)
        info["position_cm"] = self._pos.copy()
        return info


def make_real_vec_env(n_envs: int, seed: int | None = None, **kwargs: Any) -> SB3VecEnvAdapter:
    """An SB3 ``VecEnv`` of ``n_envs`` batched ``NomadOfficeReal-v0`` robots."""
    return make_sb3_vec_env(n_envs, seed, batch_class=BatchedNomadOfficeReal, **kwargs)
