"""N Nomad robots stepped in one numpy call, with the semantics of N ``NomadOffice-v0`` envs.

:class:`BatchedNomadOffice` is a ``gymnasium.vector.VectorEnv`` (same-step autoreset) that takes
every option of ``NomadOffice-v0``: on the ideal lattice model, optionally with per-step sensor noise
or with ``observation="cell"``, and off it with ``step_sd_cm`` / ``slip_sd_cm`` move noise. Sub-env
``i`` reset with seed ``s`` behaves exactly like ``gym.make("twodrl_envs:NomadOffice-v0")`` reset with seed
``s`` and reset again after every episode (same observations, rewards, terminations, truncations and,
with ``render_mode="rgb_array"``, frames). The rules are :mod:`twodrl_envs.nomad.core`'s, as the single
env's; the robot is a :class:`~twodrl_envs.nomad.core.Robot`. Stable-Baselines3 sees it through any
adapter of a same-step-autoreset ``VectorEnv`` (the bench's ``twodrl_zoo.vec_env.VectorEnvAdapter``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.nomad.core import ROUTE_LABELS, OfficeCore, Robot, office_core, remembered_route
from twodrl_envs.nomad.episode import RENDER_MODES, Counters, EnvOptions, Episodes
from twodrl_envs.nomad.office import NomadOfficeEnv

_ROUTE_NAMES = np.array(ROUTE_LABELS, dtype=object)


class BatchedNomadOffice(VectorEnv):
    """``num_envs`` robots in one office; arrays in, arrays out.

    ``info`` holds arrays ``punishment``, ``collision``, ``route`` (object: ``None``/``"shortcut"``/
    ``"detour"``; absent on a map without route regions), ``position_cm`` ``(N, 2)`` and
    ``is_success``, each with its ``_key`` mask; where an episode ended, ``final_obs``
    ``(N, obs_dim)`` (rows valid where ``_final_obs``) holds its last observation and the returned
    observation is the next episode's first. ``render()`` gives one frame per sub-env.

    With ``step_sd_cm`` / ``slip_sd_cm`` the robots leave the lattice: each sub-env draws its move
    noise from its own generator, seeded as a single env's ``np_random``, in the single env's order.
    The options besides ``num_envs`` are those of the single env :attr:`single_env` (``map``, its robot's and
    :class:`~twodrl_envs.nomad.episode.EnvOptions`', :attr:`options`), with ``max_episode_steps``
    :data:`~twodrl_envs.MAX_EPISODE_STEPS` unless given. The episode's start, moves, observation and ``info`` are
    :class:`~twodrl_envs.nomad.episode.Episodes`' (:attr:`episodes`), and its counters and time limit
    :class:`~twodrl_envs.nomad.episode.Counters`', as the single env's.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": list(RENDER_MODES)}

    single_env: ClassVar[type[NomadOfficeEnv]] = NomadOfficeEnv
    """The single env whose options (its robot's: its ``robot_factory``) this batch takes, and whose robot it moves."""

    def __init__(self, num_envs: int, map: str | Path | None = None, **options: Any) -> None:
        factory = self.single_env.robot_factory
        checked, robot_options = EnvOptions.split(type(self), factory, options)
        core = office_core(map)
        self._setup(num_envs, core, factory(core, self._generators, **robot_options), checked)

    def _setup(self, num_envs: int, core: OfficeCore, robot: Robot, options: EnvOptions) -> None:
        """Spaces and state of ``num_envs`` ``robot``s in ``core``'s office (every variant's constructor ends here)."""
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive int, got {num_envs!r}")
        self.episodes = Episodes(core, robot, options, type(self).__name__)
        self.core, self.robot, self.options, self.render_mode = core, robot, options, options.render_mode
        self.observation, self.observe_odometry = options.observation, options.observe_odometry
        self.starts, self.progress = options.starts, options.progress
        self.num_envs = int(num_envs)
        limit = options.max_episode_steps
        self.max_episode_steps = MAX_EPISODE_STEPS if limit is None else limit
        self.single_observation_space = self.episodes.observation_space
        self.single_action_space = spaces.Discrete(4)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._all = np.ones(self.num_envs, dtype=bool)
        self._all.flags.writeable = False
        self._cell = np.full(self.num_envs, core.start_cell)
        self._route = np.zeros(self.num_envs, dtype=np.int8)
        self._counters = Counters(self.num_envs, self.max_episode_steps)
        # robot centres (cm) and their dead-reckoned odometry (off the lattice; on it, the centres)
        self._pos = np.repeat(np.array(core.office.start, dtype=np.float64)[None], self.num_envs, axis=0)
        self._odo = self._pos.copy()
        self._rngs: list[np.random.Generator] = []
        self._trajectories: list[list[tuple[float, float]]] = [[] for _ in range(self.num_envs)]

    def _generators(self) -> list[np.random.Generator]:
        """The generators the ideal robot's move noise draws from: sub-env ``i``'s, seeded as a single env's."""
        return self._rngs

    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every robot to the start; ``seed=s`` seeds sub-env ``i`` with ``s + i``. A sub-env given no seed
        keeps its generator and noise base key, as a single env reset without a seed does (Gymnasium's
        ``Env.reset``); one never seeded draws them from the OS."""
        if options:
            raise ValueError(f"{type(self).__name__}.reset takes no options, got {options!r}")
        if seed is None or isinstance(seed, int | np.integer):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed must be an int or {self.num_envs} seeds, got {len(seeds)}")
        fresh = not self._rngs
        rows = np.array([fresh or s is not None for s in seeds])
        drawn = [seeding.np_random(s) for s, row in zip(seeds, rows, strict=True) if row]
        if fresh:
            self._rngs.extend(rng for rng, _ in drawn)  # the robot reads this list (_generators)
        else:
            for i, (rng, _) in zip(np.flatnonzero(rows), drawn, strict=True):
                self._rngs[i] = rng
        if rows[0]:
            self._np_random, self._np_random_seed = drawn[0]
        self._counters.seed([rng for rng, _ in drawn], rows)
        self._restart(self._all)
        obs = self._observe(self._all)
        zeros = np.zeros(self.num_envs, dtype=bool)
        return obs, self._info(np.zeros(self.num_envs), zeros, zeros)

    def _restart(self, rows: np.ndarray) -> None:
        """Count a new episode of the robots ``rows`` (bool mask) and put them at its start (as ``starts`` says)."""
        self._counters.begin(rows)
        start = self.episodes.start(self._counters.keys[rows])
        self._cell[rows], self._route[rows] = start.cells, start.routes
        self._pos[rows] = self._odo[rows] = start.positions
        if self.render_mode is not None:
            for i in np.flatnonzero(rows):
                self._trajectories[i] = [tuple(self._pos[i])]

    def _observe(self, rows: np.ndarray) -> np.ndarray:
        counters = self._counters
        return self.episodes.observe(rows, self._cell, self._pos, self._odo, counters.keys, counters.steps)

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Move every robot (eq. 11-12 evaluations); finished robots restart in the same call."""
        actions = np.asarray(actions)
        if actions.shape != (self.num_envs,) or not np.all((actions >= 0) & (actions < 4)):
            raise ValueError(f"actions must be {self.num_envs} integers in 0..3, got {actions!r}")
        actions = actions.astype(np.intp)
        counters = self._counters
        counters.steps += 1
        move = self.episodes.move(self._cell, self._pos, self._odo, actions, counters.keys, counters.steps)
        self._cell, self._pos, self._odo = move.cells, move.positions, move.odometry
        collided, goal, rewards, punishment = move.collided, move.goal, move.reward, move.punishment
        self._route = remembered_route(self._route, move.code).astype(np.int8)
        terminated = collided | goal
        truncated = counters.truncated(terminated)
        obs = self._observe(self._all)
        info = self._info(punishment, collided, goal)
        if self.render_mode is not None:
            for trajectory, xy in zip(self._trajectories, self._pos, strict=True):
                trajectory.append(tuple(xy))
        done = terminated | truncated
        if done.any():
            info["final_obs"], info["_final_obs"] = obs.copy(), done
            self._restart(done)
            obs[done] = self._observe(done)
        return obs, rewards, terminated, truncated, info

    def _info(self, punishment: np.ndarray, collided: np.ndarray, goal: np.ndarray) -> dict[str, Any]:
        info = self.episodes.info(punishment, collided, _ROUTE_NAMES[self._route], self._pos.copy(), goal)
        info.update({f"_{key}": self._all for key in self.episodes.info_keys})
        return info

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One top-down RGB frame per sub-env (``render_mode="rgb_array"``), as each single env renders."""
        if self.render_mode != "rgb_array":
            return None
        return tuple(
            self.episodes.frame(xy, trajectory) for xy, trajectory in zip(self._pos, self._trajectories, strict=True)
        )
