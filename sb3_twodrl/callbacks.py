"""Episode metrics for any SB3 algorithm: goal rate, reward per step, route shares, collisions.

The metrics are those of the 2D-RL paper's figures 3-5, computed from what the environment reports in
``info`` at the end of each episode, so the callback works with any algorithm (A2C, TwoDimA2C, PPO, ...)
and any environment that sets the keys below.

Keys read from ``info`` (all optional):

- ``"episode"``: ``{"r": return, "l": length}``, set by SB3's ``Monitor``/``VecMonitor`` at the
  end of an episode. When it is missing, the callback sums the rewards it sees itself
  (``self.locals["rewards"]``), which are the *normalised* rewards if ``VecNormalize`` is used.
- ``"is_success"``: whether the episode reached the goal (read at the episode's last step).
- ``"route"``: a label of the way the episode went (any string, e.g. the office's ``"shortcut"`` and
  ``"detour"``) or ``None`` (none yet). The label of an episode is the last non-``None`` label seen during it.
- ``"collision"``: whether a step collided; an episode collided if any of its steps did.
"""

from __future__ import annotations

import copy
import math
import warnings
from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, EvalCallback

__all__ = [
    "PATIENCE",
    "SUCCESS_THRESHOLD",
    "EpisodeRecord",
    "EpisodeTracker",
    "GoalCheck",
    "GoalCheckCallback",
    "GoalRecord",
    "NavigationMetricsCallback",
    "StopAfterEpisodes",
    "summarize_episodes",
]


@dataclass(frozen=True)
class EpisodeRecord:
    """What one finished episode contributes to the metrics."""

    episode_return: float
    length: int
    success: bool | None = None  # None: the env never said (no "is_success" key)
    route: str | None = None  # last non-None info["route"] of the episode
    collision: bool | None = None  # None: the env never said (no "collision" key)
    has_route_key: bool = False  # the env sets info["route"] at all


def _check_routes(routes: Sequence[str]) -> tuple[str, ...]:
    """``routes`` as a tuple; ``TypeError`` unless a sequence of strings (a string itself is not one)."""
    if isinstance(routes, str) or not all(isinstance(route, str) for route in routes):
        raise TypeError(f"routes must be a sequence of route labels (strings), got {routes!r}")
    return tuple(routes)


def summarize_episodes(episodes: Iterable[EpisodeRecord], routes: Sequence[str] = ()) -> dict[str, float]:
    """Metrics over a set of finished episodes (the definitions used everywhere in this package).

    - ``goal_rate``: share of episodes with ``is_success`` true, over the episodes that carry the key.
    - ``reward_per_step``: mean over episodes of (episode return / episode length) (paper, figure 4).
    - ``<label>_share``: for each label in ``routes`` and each other label an episode carries, its share
      among the episodes whose route is labelled (the shares sum to 1). Episodes that ended before
      taking a route (e.g. an early collision) do not count. NaN when no episode is labelled.
    - ``collision_rate``: share of episodes in which a collision happened.
    - ``episodes``: how many episodes were summarised; ``labelled_episodes``: how many carry a route.

    A metric whose key the env never set is absent from the result (the route metrics: unless an episode
    carries the ``route`` key); a metric over an empty set is NaN.
    """
    routes = _check_routes(routes)
    eps = list(episodes)
    out: dict[str, float] = {"episodes": float(len(eps))}
    nan = math.nan
    if eps:
        out["reward_per_step"] = float(np.mean([e.episode_return / max(e.length, 1) for e in eps]))
    else:
        out["reward_per_step"] = nan
    flagged = [e.success for e in eps if e.success is not None]
    if flagged or not eps:
        out["goal_rate"] = float(np.mean(flagged)) if flagged else nan
    collided = [e.collision for e in eps if e.collision is not None]
    if collided or not eps:
        out["collision_rate"] = float(np.mean(collided)) if collided else nan
    if any(e.has_route_key for e in eps) or not eps:
        labelled = [e.route for e in eps if e.route is not None]
        out["labelled_episodes"] = float(len(labelled))
        for label in dict.fromkeys([*routes, *labelled]):
            out[f"{label}_share"] = labelled.count(label) / len(labelled) if labelled else nan
    return out


class EpisodeTracker:
    """Follows ``n_envs`` parallel environments step by step and emits one record per finished episode."""

    def __init__(self, n_envs: int) -> None:
        self.n_envs = n_envs
        self._returns = np.zeros(n_envs, dtype=np.float64)
        self._lengths = np.zeros(n_envs, dtype=np.int64)
        self._routes: list[str | None] = [None] * n_envs
        self._collided: list[bool | None] = [None] * n_envs
        self._route_key = [False] * n_envs

    def reset(self, env_index: int | None = None) -> None:
        indices = range(self.n_envs) if env_index is None else [env_index]
        for i in indices:
            self._returns[i] = 0.0
            self._lengths[i] = 0
            self._routes[i] = None
            self._collided[i] = None
            self._route_key[i] = False

    def step(
        self,
        infos: Sequence[Mapping[str, Any]],
        dones: Sequence[bool] | np.ndarray,
        rewards: Sequence[float] | np.ndarray | None = None,
    ) -> list[EpisodeRecord]:
        """Account for one vectorised step; returns the records of the episodes that ended in it."""
        if rewards is not None:
            self._returns += np.asarray(rewards, dtype=np.float64).reshape(self.n_envs)
        self._lengths += 1
        routes, collided, route_key = self._routes, self._collided, self._route_key
        for i, info in enumerate(infos):
            if "route" in info:
                route_key[i] = True
                route = info["route"]
                if route is not None:
                    routes[i] = str(route)
            if "collision" in info:
                collided[i] = bool(collided[i]) or bool(info["collision"])
        finished: list[EpisodeRecord] = []
        for i in np.flatnonzero(dones).tolist():
            info = infos[i]
            ep_return, ep_length = float(self._returns[i]), int(self._lengths[i])
            episode = info.get("episode")
            if episode is not None:
                ep_return, ep_length = float(episode["r"]), int(episode["l"])
            success = info.get("is_success")
            finished.append(
                EpisodeRecord(
                    episode_return=ep_return,
                    length=ep_length,
                    success=None if success is None else bool(success),
                    route=routes[i],
                    collision=collided[i],
                    has_route_key=route_key[i],
                )
            )
            self.reset(i)
        return finished


class NavigationMetricsCallback(BaseCallback):
    """Logs the paper's navigation metrics to SB3's logger (so to TensorBoard) at every rollout end.

    Keys: ``rollout/goal_rate``, ``rollout/reward_per_step``, ``rollout/<label>_share`` for each route
    label, ``rollout/collision_rate`` (definitions: :func:`summarize_episodes`), computed over the last
    ``window`` finished episodes (like SB3's ``rollout/ep_rew_mean``, which uses the last 100). Nothing
    is logged before the first episode ends. Route shares are logged only for envs that set
    ``info["route"]``: one per label in ``routes`` (NaN while no episode in the window is labelled) and
    one per other label, from the first episode that carries it on; the goal rate only for envs that set
    ``info["is_success"]``, the collision rate only for envs that set ``info["collision"]``.

    It reads ``infos``, ``dones`` (and ``rewards`` only when ``info["episode"]`` is absent) from
    ``self.locals``, so it works with any SB3 algorithm.

    :param routes: route labels whose share is logged from the start (e.g. ``["shortcut", "detour"]``)
    """

    def __init__(
        self, window: int = 100, prefix: str = "rollout", routes: Sequence[str] = (), verbose: int = 0
    ) -> None:
        super().__init__(verbose)
        if window < 1:
            raise ValueError(f"window must be >= 1, got {window}")
        self.window = window
        self.prefix = prefix
        self.routes = _check_routes(routes)
        self.episodes: deque[EpisodeRecord] = deque(maxlen=window)
        self.total_episodes = 0
        self._tracker: EpisodeTracker | None = None

    def _init_callback(self) -> None:
        self._tracker = EpisodeTracker(self.training_env.num_envs)

    def _on_step(self) -> bool:
        assert self._tracker is not None
        finished = self._tracker.step(self.locals["infos"], self.locals["dones"], self.locals.get("rewards"))
        self.episodes.extend(finished)
        self.total_episodes += len(finished)
        new_routes = [e.route for e in finished if e.route is not None and e.route not in self.routes]
        self.routes += tuple(dict.fromkeys(new_routes))
        return True

    def metrics(self) -> dict[str, float]:
        """The current metrics over the window (see :func:`summarize_episodes`), a share for every route seen."""
        return summarize_episodes(self.episodes, self.routes)

    def _on_rollout_end(self) -> None:
        if not self.episodes:
            return
        for key, value in self.metrics().items():
            if key in ("episodes", "labelled_episodes"):
                continue
            self.logger.record(f"{self.prefix}/{key}", value)


class StopAfterEpisodes(BaseCallback):
    """Stops ``learn()`` once ``max_episodes`` episodes have finished, counted over all envs.

    Unlike SB3's ``StopTrainingOnMaxEpisodes`` (which stops after ``max_episodes`` episodes *per
    env*), the count here is the total, which is what "K learning episodes" means in the paper.
    """

    def __init__(self, max_episodes: int, verbose: int = 0) -> None:
        super().__init__(verbose)
        self.max_episodes = max_episodes
        self.n_episodes = 0

    def _on_step(self) -> bool:
        self.n_episodes += int(np.sum(self.locals["dones"]))
        return self.n_episodes < self.max_episodes


SUCCESS_THRESHOLD = 0.8
"""The goal rate at which a navigation task counts as learned (the paper's 80% of test trials, section 3.4): the
default of :class:`GoalRecord` and :class:`GoalCheckCallback`, and the one threshold of the commands and the bench."""
PATIENCE = 2
"""Consecutive checks at :data:`SUCCESS_THRESHOLD` after which a task counts as learned (the default)."""


@dataclass(frozen=True)
class GoalCheck:
    """One check of :class:`GoalCheckCallback`: when, the share of its episodes that reached the goal, their mean
    return."""

    timesteps: int
    goal_rate: float
    mean_return: float


class GoalRecord:
    """The goal checks of one training run: which check's policy to keep and whether the task is learned.

    The kept check is the best so far: the highest goal rate, then the highest mean return, then the later check.
    The task is learned once ``patience`` consecutive checks reach ``success_threshold`` (None: never).

    :raises ValueError: if ``success_threshold`` is not in (0, 1] or ``patience`` is not a positive int
    """

    def __init__(self, success_threshold: float | None = SUCCESS_THRESHOLD, patience: int = PATIENCE) -> None:
        if success_threshold is not None and not 0.0 < success_threshold <= 1.0:
            raise ValueError(f"success_threshold must be in (0, 1] or None, got {success_threshold!r}")
        if isinstance(patience, bool) or not isinstance(patience, int) or patience < 1:
            raise ValueError(f"patience must be a positive int, got {patience!r}")
        self.success_threshold, self.patience = success_threshold, patience
        self.checks: list[GoalCheck] = []
        self.kept: GoalCheck | None = None

    def add(self, check: GoalCheck) -> bool:
        """Record ``check``; whether it is the new one to keep."""
        self.checks.append(check)
        if self.kept is None or (check.goal_rate, check.mean_return) >= (self.kept.goal_rate, self.kept.mean_return):
            self.kept = check
            return True
        return False

    @property
    def passed(self) -> bool:
        """Whether any check reached ``success_threshold`` (False when it is None)."""
        threshold = self.success_threshold
        return threshold is not None and any(c.goal_rate >= threshold for c in self.checks)

    @property
    def learned(self) -> bool:
        """Whether the last ``patience`` checks all reached ``success_threshold``."""
        recent = self.checks[-self.patience :]
        threshold = self.success_threshold
        return threshold is not None and len(recent) == self.patience and all(c.goal_rate >= threshold for c in recent)


class GoalCheckCallback(EvalCallback):
    """SB3's ``EvalCallback`` that keeps the policy that reached the goal and stops training once it has learned.

    Every ``eval_freq`` calls (``eval_freq * n_envs`` timesteps) it runs ``n_eval_episodes`` episodes on
    ``eval_env`` (deterministic by default, e.g. from a map's start) as ``EvalCallback`` does, logging
    ``eval/success_rate``; the check's **goal rate** is the share of them whose last ``info["is_success"]`` is true.

    - **Keeps what worked:** a copy of the policy's parameters (and of ``VecNormalize``'s statistics) at the best
      check so far (:class:`GoalRecord`: the highest goal rate, then the highest mean return, then the later
      check). When training ends (the budget spent, or stopped) the kept parameters are loaded back into the model,
      so ``model.save`` saves that policy; :attr:`kept` says which check it was.
    - **Stops when learned:** once ``patience`` consecutive checks reach ``success_threshold`` (None: never
      stops early); the budget is then a ceiling. :attr:`learned_at` is the timestep of the last of them.

    An ``eval_env`` whose episodes never report ``is_success`` gets a warning and the plain ``EvalCallback``
    behaviour (nothing kept, no early stop). Other arguments are ``EvalCallback``'s.

    :raises ValueError: if ``success_threshold`` is not in (0, 1] or ``patience`` is not a positive int
    """

    def __init__(
        self,
        eval_env: Any,
        success_threshold: float | None = SUCCESS_THRESHOLD,
        patience: int = PATIENCE,
        eval_freq: int = 10_000,
        n_eval_episodes: int = 5,
        deterministic: bool = True,
        **kwargs: Any,
    ) -> None:
        self.record = GoalRecord(success_threshold, patience)
        super().__init__(
            eval_env, eval_freq=eval_freq, n_eval_episodes=n_eval_episodes, deterministic=deterministic, **kwargs
        )
        self.learned_at: int | None = None
        self._kept_state: tuple[dict[str, Any], Any] | None = None
        self._reports_success = True

    @property
    def checks(self) -> list[GoalCheck]:
        """Every check so far."""
        return self.record.checks

    @property
    def kept(self) -> GoalCheck | None:
        """The check whose policy is kept, None before the first."""
        return self.record.kept

    def _on_step(self) -> bool:
        checked = self.eval_freq > 0 and self.n_calls % self.eval_freq == 0
        continue_training = super()._on_step()
        if not checked or not self._reports_success:
            return continue_training
        if not self._is_success_buffer:
            warnings.warn("GoalCheckCallback: eval_env reports no info['is_success']; keeping nothing", stacklevel=2)
            self._reports_success = False
            return continue_training
        check = GoalCheck(self.num_timesteps, float(np.mean(self._is_success_buffer)), self.last_mean_reward)
        if self.record.add(check):
            statistics = self.model.get_vec_normalize_env()
            self._kept_state = (
                copy.deepcopy(self.model.policy.state_dict()),
                None if statistics is None else copy.deepcopy((statistics.obs_rms, statistics.ret_rms)),
            )
        if self.record.learned:
            self.learned_at = self.num_timesteps
            if self.verbose >= 1:
                threshold, patience = self.record.success_threshold, self.record.patience
                print(f"Learned: goal rate >= {threshold} in {patience} checks in a row, stopping")
            return False
        return continue_training

    def _on_training_end(self) -> None:
        if self._kept_state is None:
            return
        parameters, statistics = self._kept_state
        self.model.policy.load_state_dict(parameters)
        vec_normalize = self.model.get_vec_normalize_env()
        if vec_normalize is not None and statistics is not None:
            vec_normalize.obs_rms, vec_normalize.ret_rms = copy.deepcopy(statistics)
