"""The default office poses the paper's dilemma (properties P1-P5, docs/nomad.md) before any learning.

The figures are exact (``twodrl_envs.analysis.dilemma``); one test checks them against walks of the batched env.
"""

import gymnasium as gym
import numpy as np
import pytest

from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.analysis.dilemma import (
    GAMMA,
    eps_policy,
    expected_return,
    follower_actions,
    goal_probabilities,
    measure,
    properties,
    route_length,
    wall_avoiding_policy,
)
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_envs.nomad.core import office_core

EPS_GRID = np.array([0.1, 0.2, 0.25, 0.3, 0.35])


@pytest.fixture(scope="module")
def office():
    return measure(office_core(), MAX_EPISODE_STEPS, EPS_GRID)


def test_p1_precise_favours_the_shortcut_unstable_the_detour(office):
    assert office["shortcut_return_eps0.05"] > office["detour_return_eps0.05"]
    assert office["detour_goal_rate_eps0.3"] >= 1.3 * office["shortcut_goal_rate_eps0.3"]
    assert office["detour_return_eps0.3"] >= office["shortcut_return_eps0.3"]
    assert 0.05 < office["crossover_eps"] <= 0.3


def test_p2_both_routes_are_worth_taking(office):
    assert office["detour_exact_return"] >= 0.15 > office["avoider_return"] + 0.2
    assert office["shortcut_exact_return"] >= 1.5 * office["detour_exact_return"]


def test_p3_p4_the_shortcut_is_short_and_risky(office):
    assert 0 < office["shortcut_moves"] <= 0.65 * office["detour_moves"]
    assert office["shortcut_collisions_per_step"] >= 2.0 * office["detour_collisions_per_step"]


def test_p5_wall_avoiding_walks_find_the_detour(office):
    assert office["avoider_goal_limit"] >= 0.01
    assert office["avoider_goal_detour_limit"] >= 0.25 * office["avoider_goal_limit"]
    assert office["avoider_goal_detour_2limit"] > office["avoider_goal_detour_limit"]
    assert all(properties(office).values())


def test_open_office_lacks_the_dilemma():
    held = properties(measure(office_core("open"), MAX_EPISODE_STEPS, EPS_GRID))
    assert not held["P1"] and not held["P2"] and not held["P5"]


@pytest.mark.parametrize("route", ["shortcut", "detour"])
def test_each_routes_shortest_path_carries_its_label(route):
    core = office_core()
    actions = follower_actions(core, route)
    env = gym.make("twodrl_envs:NomadOffice-v0")
    env.reset(seed=0)
    cell, steps = core.start_cell, 0
    while True:
        *_, terminated, truncated, info = env.step(int(actions[cell]))
        cell, steps = core.lattice.index(info["position_cm"]), steps + 1
        if terminated or truncated:
            break
    assert info["is_success"] and info["route"] == route and steps == route_length(core, route)


def _batched_walks(policy, n, seed):
    """First episodes of ``n`` batched robots acting by ``policy`` ``(n_cells, 4)``: return, goal, route."""
    env = BatchedNomadOffice(n)
    core = env.core
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    cell = np.full(n, core.start_cell)
    ret, discount = np.zeros(n), np.ones(n)
    goal, route, alive = np.zeros(n, bool), np.full(n, None, dtype=object), np.ones(n, bool)
    cumulative = np.cumsum(policy, axis=1)
    for _ in range(MAX_EPISODE_STEPS):
        actions = np.minimum((rng.random((n, 1)) > cumulative[cell]).sum(axis=1), 3)
        _, reward, terminated, truncated, info = env.step(actions)
        ret += alive * discount * reward
        discount *= GAMMA
        ended = alive & (terminated | truncated)
        goal |= ended & info["is_success"]
        route[ended] = info["route"][ended]
        alive &= ~ended
        xy = info["position_cm"]
        ix = np.round((xy[:, 0] - core.lattice.origin[0]) / 10).astype(int)
        iy = np.round((xy[:, 1] - core.lattice.origin[1]) / 10).astype(int)
        cell = np.where(alive, core.lattice.grid[ix, iy], core.start_cell)
    return ret, goal, route


def test_exact_figures_match_walks_of_the_batched_env():
    core = office_core()
    n = 4000
    policy = eps_policy(core, "shortcut", 0.3)
    ret, goal, _ = _batched_walks(policy, n, seed=0)
    exact_goal = goal_probabilities(core, policy, (MAX_EPISODE_STEPS,))[MAX_EPISODE_STEPS].sum()
    assert goal.mean() == pytest.approx(exact_goal, abs=4 * np.sqrt(exact_goal * (1 - exact_goal) / n))
    assert ret.mean() == pytest.approx(expected_return(core, policy, MAX_EPISODE_STEPS), abs=4 * ret.std() / np.sqrt(n))
    walk = wall_avoiding_policy(core)
    _, goal, route = _batched_walks(walk, n, seed=1)
    exact = goal_probabilities(core, walk, (MAX_EPISODE_STEPS,))[MAX_EPISODE_STEPS]
    for label, p in (("shortcut", exact[1]), ("detour", exact[2])):
        assert (goal & (route == label)).mean() == pytest.approx(p, abs=4 * np.sqrt(p * (1 - p) / n))


@pytest.mark.parametrize(("kwargs", "message"), [({"time_limit": 0}, "time_limit"), ({"route": "tunnel"}, "route")])
def test_bad_arguments_are_value_errors(kwargs, message):
    core = office_core()
    with pytest.raises(ValueError, match=message):
        if "route" in kwargs:
            route_length(core, kwargs["route"])
        else:
            measure(core, kwargs["time_limit"])
