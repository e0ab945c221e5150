"""N Nomad robots stepped in one numpy call, with the semantics of N ``NomadOffice-v0`` envs.

:class:`BatchedNomadOffice` is a ``gymnasium.vector.VectorEnv`` (same-step autoreset) that takes
every option of ``NomadOffice-v0``: on the ideal lattice model, optionally with per-step sensor noise
or with ``observation="cell"``, and off it with ``step_sd_cm`` / ``slip_sd_cm`` move noise. Sub-env
``i`` reset with seed ``s`` behaves exactly like ``gym.make("twodrl_envs:NomadOffice-v0")`` reset with seed
``s`` and reset again after every episode (same observations, rewards, terminations, truncations and,
with ``render_mode="rgb_array"``, frames). :class:`SB3VecEnvAdapter` exposes it to Stable-Baselines3
as a ``VecEnv``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvStepReturn
from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, STEP_CM, swept_clearance
from twodrl_envs.nomad.office import (
    COLLISION_PUNISHMENT,
    GOAL_REWARD,
    MOVE_PUNISHMENT,
    ROUTES,
    NomadOfficeEnv,
    episode_keys,
    route_code_at,
)
from twodrl_envs.nomad.sensors import NoiseModel

_ROUTE_NAMES = np.array(ROUTES, dtype=object)
_INFO_KEYS = ("punishment", "collision", "route", "position_cm", "is_success")


class BatchedNomadOffice(VectorEnv):
    """``num_envs`` robots in one office; arrays in, arrays out.

    ``info`` holds arrays ``punishment``, ``collision``, ``route`` (object: ``None``/``"shortcut"``/
    ``"detour"``; absent on a map without route regions), ``position_cm`` ``(N, 2)`` and
    ``is_success``, each with its ``_key`` mask; where an episode ended, ``final_obs``
    ``(N, obs_dim)`` (rows valid where ``_final_obs``) holds its last observation and the returned
    observation is the next episode's first. ``render()`` gives one frame per sub-env.

    With ``step_sd_cm`` / ``slip_sd_cm`` the robots leave the lattice: each sub-env draws its move
    noise from its own generator, seeded as a single env's ``np_random``, in the single env's order.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array"]}

    def __init__(
        self,
        num_envs: int,
        map: str | Path | None = None,
        *,
        observe_odometry: bool = True,
        sensor_noise: bool | NoiseModel | None = None,
        step_sd_cm: float = 0.0,
        slip_sd_cm: float = 0.0,
        render_mode: str | None = None,
        max_episode_steps: int = MAX_EPISODE_STEPS,
        observation: str = "sensors",
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive int, got {num_envs!r}")
        if isinstance(max_episode_steps, bool) or not isinstance(max_episode_steps, int) or max_episode_steps < 1:
            raise ValueError(f"max_episode_steps must be a positive int, got {max_episode_steps!r}")
        template = NomadOfficeEnv(
            map,
            observe_odometry=observe_odometry,
            sensor_noise=sensor_noise,
            step_sd_cm=step_sd_cm,
            slip_sd_cm=slip_sd_cm,
            render_mode=render_mode,
            observation=observation,
        )
        self.core, self.noise, self.observation = template.core, template.noise, template.observation
        self.step_sd_cm, self.slip_sd_cm, self.render_mode = template.step_sd_cm, template.slip_sd_cm, render_mode
        self._lattice = template._on_lattice_motion  # False: continuous poses (a subclass may set it so too)
        self.num_envs = int(num_envs)
        self.max_episode_steps = max_episode_steps
        self.single_observation_space = template.observation_space
        self.single_action_space = template.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        odometry = self.core.odometry(self.core.lattice.cells)
        table = np.concatenate([self.core.readings, odometry], axis=1)
        self._obs_table = np.ascontiguousarray(table[:, : sensors.N_READINGS + (2 if observe_odometry else 0)])
        self._sd_table = None if self.noise is None else self.noise.sd(self.core.ranges)
        self._moves = self.core.lattice.moves  # move outcomes; a replay subclass swaps in the recorded free space
        self._step_reward = np.array([-MOVE_PUNISHMENT, GOAL_REWARD - MOVE_PUNISHMENT, -COLLISION_PUNISHMENT])
        self._info_keys = tuple(k for k in _INFO_KEYS if k != "route" or self.core.office.has_routes)
        self._all = np.ones(self.num_envs, dtype=bool)
        self._all.flags.writeable = False
        self._cell = np.full(self.num_envs, self.core.start_cell)
        self._route = np.zeros(self.num_envs, dtype=np.int8)
        self._t = np.zeros(self.num_envs, dtype=np.int64)
        self._episode = np.zeros(self.num_envs, dtype=np.int64)
        self._base = np.zeros(self.num_envs, dtype=np.uint64)
        self._key = np.zeros(self.num_envs, dtype=np.uint64)
        # continuous poses (off the lattice): true position, dead-reckoned odometry
        self._start = np.array(self.core.office.start, dtype=np.float64)
        self._start_route = int(route_code_at(self.core.office, self._start))
        self._pos = np.repeat(self._start[None], self.num_envs, axis=0)
        self._odo = self._pos.copy()
        self._rngs: list[np.random.Generator] = []
        self._trajectories: list[list[tuple[float, float]]] = [[] for _ in range(self.num_envs)]
        self._renderer = None

    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every robot to the start; ``seed=s`` seeds sub-env ``i`` with ``s + i``."""
        if options:
            raise ValueError(f"{type(self).__name__}.reset takes no options, got {options!r}")
        if seed is None or isinstance(seed, int | np.integer):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed must be an int or {self.num_envs} seeds, got {len(seeds)}")
        self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
        self._rngs = [self._np_random] + [seeding.np_random(s)[0] for s in seeds[1:]]
        for i, rng in enumerate(self._rngs):
            self._base[i] = rng.integers(0, 2**63, size=1, dtype=np.uint64)[0]
        self._episode[:] = 0
        self._key = episode_keys(self._base, self._episode)
        self._restart(self._all)
        obs = self._observe(self._all)
        zeros = np.zeros(self.num_envs, dtype=bool)
        return obs, self._info(np.zeros(self.num_envs), zeros, zeros)

    def _restart(self, rows: np.ndarray) -> None:
        """Put the robots ``rows`` (bool mask) back at the start of a new episode."""
        self._cell[rows] = self.core.start_cell
        self._pos[rows] = self._start
        self._odo[rows] = self._start
        self._route[rows] = self._start_route
        self._t[rows] = 0
        if self.render_mode is not None:
            positions = self._positions()
            for i in np.flatnonzero(rows):
                self._trajectories[i] = [tuple(positions[i])]

    def _positions(self) -> np.ndarray:
        """Robot centres ``(N, 2)`` in cm: the lattice cells' or the continuous poses."""
        return self.core.lattice.cells[self._cell] if self._lattice else self._pos

    def _observe(self, rows: np.ndarray) -> np.ndarray:
        if self.observation == "cell":
            return self._cell[rows]  # fancy indexing: a copy
        if not self._lattice:
            readings = self._pose_readings(self._pos[rows], self._key[rows], self._t[rows])
            if not self.single_observation_space.shape[0] > sensors.N_READINGS:
                return readings
            return np.concatenate([readings, self.core.odometry(self._odo[rows])], axis=1)
        cells = self._cell[rows]
        obs = self._obs_table[cells]
        if self.noise is not None:
            ranges = self.noise.apply(self.core.ranges[cells], self._key[rows], self._t[rows], self._sd_table[cells])
            obs[:, : sensors.N_READINGS] = sensors.normalise(ranges)
        return obs

    def _pose_readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Normalised readings ``(n, 32)`` at continuous poses: exact ranges plus the sensor noise."""
        ranges = sensors.exact_ranges(self.core.office, positions)
        if self.noise is not None:
            ranges = self.noise.apply(ranges, keys, steps)
        return sensors.normalise(ranges)

    def _displacement(self, actions: np.ndarray) -> np.ndarray:
        """True moves ``(N, 2)`` cm of ``actions``: the command plus ``step_sd_cm`` along, ``slip_sd_cm`` across."""
        command = MOVES_CM[actions]
        along = [rng.normal(0.0, self.step_sd_cm) if self.step_sd_cm else 0.0 for rng in self._rngs]
        lateral = [rng.normal(0.0, self.slip_sd_cm) if self.slip_sd_cm else 0.0 for rng in self._rngs]
        unit = command / STEP_CM
        normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1)
        return command + np.array(along)[:, None] * unit + np.array(lateral)[:, None] * normal

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Move every robot (eq. 11-12 evaluations); finished robots restart in the same call."""
        actions = np.asarray(actions)
        if actions.shape != (self.num_envs,) or not np.all((actions >= 0) & (actions < 4)):
            raise ValueError(f"actions must be {self.num_envs} integers in 0..3, got {actions!r}")
        actions = actions.astype(np.intp)
        self._t += 1
        if self._lattice:
            nxt = self._moves[self._cell, actions]
            collided = nxt < 0
            self._cell = np.where(collided, self._cell, nxt)
            code = self.core.route_code[self._cell]
            goal = self.core.goal[self._cell] & ~collided
        else:
            office = self.core.office
            target = self._pos + self._displacement(actions)
            clear = swept_clearance(self._pos, target, office.walls) > ROBOT_RADIUS_CM
            collided = ~(clear & office.inside_bounds(target))
            moved = ~collided
            self._pos[moved] = target[moved]
            self._odo[moved] += MOVES_CM[actions[moved]]
            code = route_code_at(office, self._pos)
            goal = office.in_region("goal", self._pos) & moved
        self._route = np.where(~collided & (code > 0), code, self._route).astype(np.int8)
        rewards = self._step_reward[np.where(collided, 2, goal.astype(np.intp))]
        terminated = collided | goal
        truncated = (self._t >= self.max_episode_steps) & ~terminated
        obs = self._observe(self._all)
        info = self._info(np.where(collided, COLLISION_PUNISHMENT, MOVE_PUNISHMENT), collided, goal)
        if self.render_mode is not None:
            for trajectory, xy in zip(self._trajectories, self._positions(), strict=True):
                trajectory.append(tuple(xy))
        done = terminated | truncated
        if done.any():
            info["final_obs"], info["_final_obs"] = obs.copy(), done
            self._episode[done] += 1
            self._key[done] = episode_keys(self._base[done], self._episode[done])
            self._restart(done)
            obs[done] = self._observe(done)
        return obs, rewards, terminated, truncated, info

    def _info(self, punishment: np.ndarray, collided: np.ndarray, goal: np.ndarray) -> dict[str, Any]:
        values = {
            "punishment": punishment,
            "collision": collided,
            "route": _ROUTE_NAMES[self._route],
            "position_cm": self._positions().copy(),
            "is_success": goal,
        }
        info: dict[str, Any] = {key: values[key] for key in self._info_keys}
        info.update({f"_{key}": self._all for key in self._info_keys})
        return info

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One top-down RGB frame per sub-env (``render_mode="rgb_array"``), as each single env renders."""
        if self.render_mode != "rgb_array":
            return None
        from twodrl_envs.nomad.render import OfficeRenderer

        if self._renderer is None:
            self._renderer = OfficeRenderer(self.core.office)
        return tuple(
            self._renderer.frame(xy, trajectory)
            for xy, trajectory in zip(self._positions(), self._trajectories, strict=True)
        )


class SB3VecEnvAdapter(VecEnv):
    """Stable-Baselines3 ``VecEnv`` view of a :class:`BatchedNomadOffice` (per-env info dicts)."""

    def __init__(self, batched: BatchedNomadOffice) -> None:
        self.batched = batched
        super().__init__(batched.num_envs, batched.single_observation_space, batched.single_action_space)
        self._actions = np.zeros(batched.num_envs, dtype=np.int64)

    def reset(self) -> np.ndarray:
        seed = None if self._seeds[0] is None else self._seeds
        obs, _ = self.batched.reset(seed=seed)
        self._reset_seeds()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions).reshape(self.num_envs)

    def step_wait(self) -> VecEnvStepReturn:
        obs, rewards, terminated, truncated, info = self.batched.step(self._actions)
        done = terminated | truncated
        infos: list[dict[str, Any]] = [
            {
                "punishment": float(p),
                "collision": bool(c),
                "position_cm": (float(xy[0]), float(xy[1])),
                "is_success": bool(g),
            }
            for p, c, xy, g in zip(
                info["punishment"], info["collision"], info["position_cm"], info["is_success"], strict=True
            )
        ]
        if "route" in info:  # maps with route regions
            for entry, route in zip(infos, info["route"], strict=True):
                entry["route"] = route
        for i in np.flatnonzero(done):
            infos[i]["terminal_observation"] = info["final_obs"][i]
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), done, infos

    def close(self) -> None:
        self.batched.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self.batched, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self.batched, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> list[Any]:
        raise NotImplementedError("BatchedNomadOffice has no per-env methods")

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._get_indices(indices))


def make_sb3_vec_env(
    n_envs: int, seed: int | None = None, batch_class: type[BatchedNomadOffice] = BatchedNomadOffice, **kwargs: Any
) -> SB3VecEnvAdapter:
    """An SB3 ``VecEnv`` of ``n_envs`` batched ``NomadOffice-v0`` robots (kwargs go to ``batch_class``)."""
    venv = SB3VecEnvAdapter(batch_class(n_envs, **kwargs))
    venv.seed(seed)
    return venv
