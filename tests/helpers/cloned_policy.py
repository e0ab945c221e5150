"""A policy that reaches the goal, in seconds: an SB3 ``A2C`` whose actor is fitted (behaviour cloning) to the
shortest lattice path's action at every reachable cell, from the ideal sensors' observations and, when given,
from a stand-in robot's readings at the same cells (so it also reads that robot's artifacts)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch as th
from stable_baselines3 import A2C

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_envs.nomad.core import Robot, office_core


def path_actions(map_name: str | None) -> tuple[np.ndarray, np.ndarray]:
    """Reachable non-goal cells ``(n,)`` and which actions ``(n, 4)`` begin a shortest lattice path to the goal."""
    env = gym.make("NomadOffice-v0", map=map_name).unwrapped
    robot: Robot = env.robot
    distance = robot.goal_distance
    moves = robot.moves
    cells = np.flatnonzero(np.isfinite(distance) & ~env.core.goal & env.core.lattice.reachable)
    ahead = np.where(moves[cells] >= 0, distance[np.maximum(moves[cells], 0)], np.inf)
    return cells, ahead == ahead.min(axis=1, keepdims=True)


def cloned_model(map_name: str | None, readers: tuple[Robot, ...] = (), copies: int = 4, epochs: int = 400) -> A2C:
    """An ``A2C`` for ``NomadOffice-v0`` on ``map_name`` whose deterministic action is the shortest path's.

    Each robot in ``readers`` adds ``copies`` readings per cell (``pose_readings`` with fresh noise keys).
    """
    th.manual_seed(0)
    core = office_core(map_name)
    cells, actions = path_actions(map_name)
    xy = core.lattice.cells[cells]
    observations = [np.concatenate([core.readings[cells], core.cell_odometry[cells]], axis=1)]
    rng = np.random.default_rng(0)
    for robot in readers:
        for _ in range(copies):
            keys = rng.integers(0, 2**63, len(cells), dtype=np.uint64)
            readings = robot.pose_readings(xy, keys, np.zeros(len(cells), dtype=np.int64))
            observations.append(np.concatenate([readings, core.cell_odometry[cells]], axis=1))
    obs = th.as_tensor(np.concatenate(observations), dtype=th.float32)
    best = th.as_tensor(np.tile(actions, (len(observations), 1)))
    model = A2C("MlpPolicy", gym.make("NomadOffice-v0", map=map_name), seed=0, device="cpu")
    optimizer = th.optim.Adam(model.policy.parameters(), lr=1e-2)
    for _ in range(epochs):
        logits = model.policy.get_distribution(obs).distribution.logits
        loss = -th.logsumexp(logits.masked_fill(~best, -th.inf), 1).add(-th.logsumexp(logits, 1)).mean()
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    return model


def reaches_goal(model: A2C, env_id: str, map_name: str | None, seed: int = 0, **options: object) -> bool:
    """Whether one deterministic episode of ``model`` from the map's start on ``env_id`` reaches the goal."""
    env = gym.make(env_id, map=map_name, **options)
    obs, _ = env.reset(seed=seed)
    while True:
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(int(action))
        if terminated or truncated:
            return bool(info["is_success"])
