"""Measure the office's dilemma (issue 4) under a uniformly random policy, before any learning.

A good office makes the detour easy to find (random walks from the start enter the detour's
passage at least twice as often as the shortcut's) and the shortcut risky (walks that enter the
shortcut's passage collide inside it more often than walks in the detour's passage collide there).
Walks follow ``NomadOffice-v0``'s exact lattice semantics and its 200-step limit.

    python scripts/check_dilemma.py --walks 100000 --seed 0
"""

from __future__ import annotations

import argparse
from collections import deque

import numpy as np

from envs import MAX_EPISODE_STEPS
from envs.nomad.office import OfficeCore, office_core


def shortest_path(core: OfficeCore, avoid_code: int) -> int:
    """Fewest moves from start to goal without entering passage ``avoid_code`` (BFS on the lattice)."""
    allowed = core.route_code != avoid_code
    dist = {core.start_cell: 0}
    queue = deque([core.start_cell])
    while queue:
        cell = queue.popleft()
        if core.goal[cell]:
            return dist[cell]
        for nxt in core.lattice.moves[cell]:
            if nxt >= 0 and allowed[nxt] and nxt not in dist:
                dist[int(nxt)] = dist[cell] + 1
                queue.append(int(nxt))
    return -1


def measure_dilemma(n_walks: int = 100_000, seed: int = 0, map_path: str | None = None) -> dict[str, float]:
    """Entry and in-passage collision frequencies of uniformly random walks from the start."""
    core = office_core(map_path)
    rng = np.random.default_rng(seed)
    rows = np.arange(n_walks)
    cell = np.full(n_walks, core.start_cell)
    alive = np.ones(n_walks, dtype=bool)
    entered = np.zeros((n_walks, 3), dtype=bool)
    collided_in = np.zeros((n_walks, 3), dtype=bool)
    steps_in = np.zeros(3)
    collisions_in = np.zeros(3)
    goal_route = np.zeros(n_walks, dtype=np.int8)
    route = np.zeros(n_walks, dtype=np.int8)
    for _ in range(MAX_EPISODE_STEPS):
        code = core.route_code[cell]
        nxt = core.lattice.moves[cell, rng.integers(4, size=n_walks)]
        hit = alive & (nxt < 0)
        collided_in[rows, code] |= hit
        np.add.at(steps_in, code[alive], 1)
        np.add.at(collisions_in, code[hit], 1)
        alive &= ~hit
        cell = np.where(alive, nxt, cell)
        new_code = core.route_code[cell]
        entered[rows, new_code] |= alive
        route = np.where(alive & (new_code > 0), new_code, route)
        goal = alive & core.goal[cell]
        goal_route[goal] = route[goal]
        alive &= ~goal
        if not alive.any():
            break
    return {
        "enter_shortcut": entered[:, 1].mean(),
        "enter_detour": entered[:, 2].mean(),
        "entry_ratio_detour_over_shortcut": entered[:, 2].mean() / max(entered[:, 1].mean(), 1e-12),
        "collide_in_shortcut_given_entered": collided_in[entered[:, 1], 1].mean(),
        "collide_in_detour_given_entered": collided_in[entered[:, 2], 2].mean(),
        "hazard_per_step_shortcut": collisions_in[1] / max(steps_in[1], 1),
        "hazard_per_step_detour": collisions_in[2] / max(steps_in[2], 1),
        "goal_via_shortcut": (goal_route == 1).mean(),
        "goal_via_detour": (goal_route == 2).mean(),
        "shortcut_moves": shortest_path(core, avoid_code=2),
        "detour_moves": shortest_path(core, avoid_code=1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--walks", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--map", default=None, help="map file (default: the shipped office)")
    args = parser.parse_args()
    result = measure_dilemma(args.walks, args.seed, args.map)
    for key, value in result.items():
        print(f"{key:36s} {value:.4f}" if isinstance(value, float) else f"{key:36s} {value}")
    easy = result["entry_ratio_detour_over_shortcut"] >= 2.0
    risky = result["collide_in_shortcut_given_entered"] > result["collide_in_detour_given_entered"]
    short = result["shortcut_moves"] <= 0.6 * result["detour_moves"]
    print(f"detour easy to find: {easy}; shortcut risky: {risky}; shortcut <= 60% of detour: {short}")


if __name__ == "__main__":
    main()
