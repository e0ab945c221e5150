"""The office's dilemma (paper section 3.3), measured exactly on the lattice before any learning.

Every figure here is an exact expectation over ``NomadOffice-v0``'s lattice semantics (eq. 11-12
evaluations, termination on collision or goal, truncation after ``time_limit`` steps: the core's
:class:`~twodrl_envs.nomad.core.LatticeOutcomes` and route memory), computed by
propagating probabilities over the free cells, not by sampling; ``tests/envs/test_nomad_dilemma.py``
checks them against walks of the batched env. Three walkers:

- the *eps-follower* of a route: with probability ``1 - eps`` the move that follows that route's
  shortest path to the goal, else a uniformly random move (the "unstable" early robot);
- the *random walk*: a uniformly random move every step;
- the *wall-avoiding walk*: each step uniform over the moves that do not collide ("a priority on
  avoiding any obstacles immediately ahead").

A route's shortest path is the shortest on the lattice that never enters the other route's label
region. The follower moves to the neighbour nearest the goal along its route (ties: the neighbour
with the larger wall clearance, then the order N, E, S, W); a move that puts it into the other
route's region, where its route has no path, is followed by the nearest way to the goal by any route.
"""

from __future__ import annotations

import numpy as np

from twodrl_envs.nomad.core import ROUTE_CODES, LatticeOutcomes, OfficeCore, goal_distances, remembered_route
from twodrl_envs.nomad.geometry import ROUTE_REGIONS, clearance

GAMMA = 0.9  # the paper's reward discount (section 3.2)


def _other_route(route: str) -> int:
    """The code of the route that is not ``route``."""
    if route not in ROUTE_REGIONS:
        raise ValueError(f"route must be one of {ROUTE_REGIONS}, got {route!r}")
    return ROUTE_CODES[ROUTE_REGIONS[1 - ROUTE_REGIONS.index(route)]]


def distance_to_goal(core: OfficeCore, route: str | None = None) -> np.ndarray:
    """Fewest moves ``(n_cells,)`` from each cell to the goal (``inf``: none), optionally along ``route`` only.

    Along a route, the other route's label region is closed (its cells get ``inf``).
    """
    passable = None if route is None else core.route_code != _other_route(route)
    return goal_distances(core, core.lattice.moves, passable)


def follower_actions(core: OfficeCore, route: str) -> np.ndarray:
    """The action ``(n_cells,)`` of the exact follower of ``route``'s shortest path (module docstring)."""
    along, anyway = distance_to_goal(core, route), distance_to_goal(core)
    moves = core.lattice.moves
    score = np.where(np.isfinite(along), along, 1e6 + anyway)
    target = np.where(moves >= 0, score[np.maximum(moves, 0)], np.inf)
    gap = clearance(core.lattice.cells, core.office.walls)
    tie = np.where(moves >= 0, gap[np.maximum(moves, 0)], -np.inf)
    # lexicographic: nearest to the goal, then most clearance, then the first action
    order = np.lexsort((np.broadcast_to(np.arange(4), moves.shape), -tie, target), axis=1)
    return order[:, 0]


def route_length(core: OfficeCore, route: str) -> int:
    """Moves of ``route``'s shortest path from the start (-1 when it has none)."""
    d = distance_to_goal(core, route)[core.start_cell]
    return int(d) if np.isfinite(d) else -1


def eps_policy(core: OfficeCore, route: str, eps: float) -> np.ndarray:
    """Action probabilities ``(n_cells, 4)`` of the eps-follower of ``route``."""
    if not 0.0 <= eps <= 1.0:
        raise ValueError(f"eps must be in [0, 1], got {eps!r}")
    policy = np.full((len(core.lattice.moves), 4), eps / 4)
    policy[np.arange(len(policy)), follower_actions(core, route)] += 1.0 - eps
    return policy


def wall_avoiding_policy(core: OfficeCore) -> np.ndarray:
    """Action probabilities ``(n_cells, 4)`` of the wall-avoiding walk: uniform over the non-colliding moves."""
    ok = (core.lattice.moves >= 0).astype(np.float64)
    return ok / np.maximum(ok.sum(axis=1, keepdims=True), 1.0)


def expected_return(core: OfficeCore, policy: np.ndarray, time_limit: int, gamma: float = GAMMA) -> float:
    """Expected discounted return from the start of a Markov ``policy`` ``(n_cells, 4)`` (eq. 11-12 rewards)."""
    out = LatticeOutcomes.of(core, core.lattice.moves)
    ends = out.collided | out.goal
    value = np.zeros(len(out.reward))
    for _ in range(time_limit):
        value = (policy * np.where(ends, out.reward, out.reward + gamma * value[out.next_cell])).sum(axis=1)
    return float(value[core.start_cell])


def goal_probabilities(core: OfficeCore, policy: np.ndarray, time_limits: tuple[int, ...]) -> dict[int, np.ndarray]:
    """Probability of reaching the goal by route label (index 0 none, 1 shortcut, 2 detour) within each limit.

    The label is ``info["route"]``'s: the label region the robot's centre entered last.
    """
    moves = core.lattice.moves
    n = len(moves)
    safe = np.maximum(moves, 0)
    code = core.route_code.astype(np.int64)
    mass = np.zeros((n, 3))
    mass[core.start_cell, code[core.start_cell]] = 1.0
    reached = np.zeros(3)
    out: dict[int, np.ndarray] = {}
    for t in range(1, max(time_limits) + 1):
        new = np.zeros_like(mass)
        for a in range(4):
            ok = moves[:, a] >= 0
            nxt = safe[ok, a]
            flow = mass[ok] * policy[ok, a, None]
            label = remembered_route(np.arange(3), code[nxt, None])
            np.add.at(new, (nxt[:, None], label), flow)
        at_goal = core.goal
        reached += new[at_goal].sum(axis=0)
        new[at_goal] = 0.0
        mass = new
        if t in time_limits:
            out[t] = reached.copy()
    return out


def collisions_per_step(core: OfficeCore, time_limit: int) -> dict[str, float]:
    """Uniformly random walks from the start: collisions per step taken inside each route's label region."""
    moves = core.lattice.moves
    n = len(moves)
    hit = (moves < 0).mean(axis=1)
    safe = np.maximum(moves, 0)
    occupancy = np.zeros(n)
    mass = np.zeros(n)
    mass[core.start_cell] = 1.0
    for _ in range(time_limit):
        occupancy += mass
        new = np.zeros(n)
        for a in range(4):
            ok = moves[:, a] >= 0
            np.add.at(new, safe[ok, a], mass[ok] / 4)
        new[core.goal] = 0.0
        mass = new
    out = {}
    for route, c in ROUTE_CODES.items():
        inside = core.route_code == c
        out[route] = float((occupancy[inside] * hit[inside]).sum() / max(occupancy[inside].sum(), 1e-300))
    return out


def mean_episode_length(core: OfficeCore, policy: np.ndarray, time_limit: int) -> float:
    """Expected steps of an episode of ``policy`` from the start (collision, goal or the limit end it)."""
    moves = core.lattice.moves
    safe = np.maximum(moves, 0)
    alive_after = (moves >= 0) & ~core.goal[safe]
    steps = np.zeros(len(moves))
    for _ in range(time_limit):
        steps = 1.0 + (policy * np.where(alive_after, steps[safe], 0.0)).sum(axis=1)
    return float(steps[core.start_cell])


def measure(core: OfficeCore, time_limit: int, eps_grid: np.ndarray | None = None) -> dict[str, float]:
    """The figures of properties P1-P5 (docs/nomad.md) for one office, episodes truncated after ``time_limit`` steps."""
    if isinstance(time_limit, bool) or not isinstance(time_limit, int) or time_limit < 1:
        raise ValueError(f"time_limit must be a positive int, got {time_limit!r}")
    if not core.office.has_routes:
        raise ValueError(f"map {core.office.source} has no route regions (shortcut, detour): it poses no dilemma")
    eps_grid = np.round(np.arange(0.0, 0.51, 0.01), 2) if eps_grid is None else eps_grid
    out: dict[str, float] = {}
    for route in ROUTE_CODES:
        out[f"{route}_moves"] = route_length(core, route)
        out[f"{route}_exact_return"] = expected_return(core, eps_policy(core, route, 0.0), time_limit)
    for eps in (0.05, 0.3):
        for route in ROUTE_CODES:
            policy = eps_policy(core, route, eps)
            out[f"{route}_return_eps{eps}"] = expected_return(core, policy, time_limit)
            reached = goal_probabilities(core, policy, (time_limit,))[time_limit]
            out[f"{route}_goal_rate_eps{eps}"] = float(reached.sum())
    crossover = np.nan
    for eps in eps_grid:
        diff = [expected_return(core, eps_policy(core, r, float(eps)), time_limit) for r in ROUTE_CODES]
        if diff[1] >= diff[0]:
            crossover = float(eps)
            break
    out["crossover_eps"] = crossover
    hazard = collisions_per_step(core, time_limit)
    for route in ROUTE_CODES:
        out[f"{route}_collisions_per_step"] = hazard[route]
    walk = wall_avoiding_policy(core)
    out["avoider_return"] = expected_return(core, walk, time_limit)
    by_limit = goal_probabilities(core, walk, (time_limit, 2 * time_limit))
    for limit, tag in ((time_limit, "limit"), (2 * time_limit, "2limit")):
        for route, c in ROUTE_CODES.items():
            out[f"avoider_goal_{route}_{tag}"] = float(by_limit[limit][c])
        out[f"avoider_goal_{tag}"] = float(by_limit[limit].sum())
    out["avoider_mean_steps"] = mean_episode_length(core, walk, time_limit)
    out["random_mean_steps"] = mean_episode_length(core, np.full((len(walk), 4), 0.25), time_limit)
    return out


def properties(m: dict[str, float]) -> dict[str, bool]:
    """Pass/fail of the pre-registered properties P1-P5 (docs/nomad.md) on the figures of :func:`measure`."""
    return {
        "P1": m["shortcut_return_eps0.05"] > m["detour_return_eps0.05"]
        and m["detour_goal_rate_eps0.3"] >= 1.3 * m["shortcut_goal_rate_eps0.3"]
        and m["detour_return_eps0.3"] >= m["shortcut_return_eps0.3"],
        "P2": m["detour_exact_return"] >= 0.15 and m["shortcut_exact_return"] >= 1.5 * m["detour_exact_return"],
        "P3": 0 < m["shortcut_moves"] <= 0.65 * m["detour_moves"],
        "P4": m["shortcut_collisions_per_step"] >= 2.0 * m["detour_collisions_per_step"],
        "P5": m["avoider_goal_limit"] >= 0.01 and m["avoider_goal_detour_limit"] >= 0.25 * m["avoider_goal_limit"],
    }
