"""The episode in one place: the time limit is the episodes' counters' (single env == batched env at the limit
step), and the options every Nomad env takes are one checked object (``EnvOptions``), named once when bad."""

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_envs.memorable.env import BatchedNomadOfficeMemorable, NomadOfficeMemorableEnv
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_envs.nomad.episode import EnvOptions
from twodrl_envs.nomad.office import NomadOfficeEnv
from twodrl_envs.nomad.physics import NomadOfficeMuJoCoEnv
from twodrl_envs.nomad.realistic import BatchedNomadOfficeReal, NomadOfficeRealEnv

PAIRS = [
    (NomadOfficeEnv, BatchedNomadOffice),
    (NomadOfficeRealEnv, BatchedNomadOfficeReal),
    (NomadOfficeMemorableEnv, BatchedNomadOfficeMemorable),
]
NORTH, EAST, WEST = 0, 1, 3


def _flags(env: Any, actions: list[int], seed: int = 3) -> list[tuple[bool, bool]]:
    """``(terminated, truncated)`` of a single env, or of sub-env 0 of a batched one, stepped by ``actions``."""
    env.reset(seed=seed)
    batched = hasattr(env, "num_envs")
    flags = []
    for action in actions:
        _, _, terminated, truncated, _ = env.step(np.array([action]) if batched else action)
        flags.append((bool(np.ravel(terminated)[0]), bool(np.ravel(truncated)[0])))
        if flags[-1] != (False, False):
            break
    return flags


@pytest.mark.parametrize(("single", "batched"), PAIRS)
def test_single_and_batched_envs_agree_at_the_limit_step(single: Any, batched: Any) -> None:
    to_wall = len(_flags(single(), [NORTH] * 500))  # north until the episode terminates (a wall, or the goal)
    assert _flags(single(), [NORTH] * 500)[-1] == (True, False) and to_wall > 1
    for limit, last in ((to_wall, (True, False)), (to_wall - 1, (False, True))):  # terminated at it / truncated
        flags = _flags(single(max_episode_steps=limit), [NORTH] * 500)
        assert flags == _flags(batched(1, max_episode_steps=limit), [NORTH] * 500)
        assert len(flags) == limit and flags[-1] == last
    wander = [EAST, WEST] * 20
    assert _flags(single(max_episode_steps=7), wander) == _flags(batched(1, max_episode_steps=7), wander)
    assert _flags(single(max_episode_steps=7), wander)[-1] == (False, True)


def test_a_single_env_without_a_limit_leaves_it_to_gym_make() -> None:
    assert _flags(NomadOfficeEnv(), [EAST, WEST] * 200)[-1] == (False, False)  # no limit of its own
    limit = len(_flags(NomadOfficeEnv(), [NORTH] * 500))
    # gym.make's TimeLimit (outside the env) ends the episode at the limit step; where the episode terminated there,
    # TimeLimit may flag it truncated too (the batched env does not)
    flags = _flags(gym.make("NomadOffice-v0", max_episode_steps=limit), [NORTH] * 500)
    assert len(flags) == limit and flags[-1][0]
    assert _flags(gym.make("NomadOffice-v0", max_episode_steps=7), [EAST, WEST] * 20)[-1] == (False, True)


CONSTRUCTORS = [
    *(env for pair in PAIRS for env in pair),
    NomadOfficeMuJoCoEnv,  # checked before mujoco is imported
]
BAD = [
    ("observe_odometry", "yes", TypeError),
    ("render_mode", "human", ValueError),
    ("observation", "pixels", ValueError),
    ("starts", "anywhere", ValueError),
    ("progress", -0.5, ValueError),
    ("max_episode_steps", 0, ValueError),
]


def _make(env: Any, **options: Any) -> Any:
    return env(2, **options) if "Batched" in env.__name__ else env(**options)


def _error(env: Any, **options: Any) -> tuple[type[BaseException], str]:
    with pytest.raises((TypeError, ValueError)) as raised:
        _make(env, **options)
    return raised.type, str(raised.value)


@pytest.mark.parametrize(("option", "value", "error"), BAD)
def test_a_bad_option_is_named_once_by_one_check(option: str, value: Any, error: type[Exception]) -> None:
    made = [_error(env, **{option: value}) for env in CONSTRUCTORS]
    assert {kind for kind, _ in made} == {error}
    assert all(message.count(option) == 1 and repr(value) in message for _, message in made), made
    same = made[:-1] if option == "render_mode" else made  # the MuJoCo env has a render mode of its own
    assert len(set(same)) == 1, same
    with pytest.raises(error, match=option):
        EnvOptions(**{option: value})


def test_every_constructor_takes_the_options_and_refuses_other_keywords() -> None:
    options = {"observe_odometry": False, "starts": "uniform", "max_episode_steps": 40}
    for env in CONSTRUCTORS[:-1]:
        assert _make(env, **options).options == EnvOptions(**options)
        unexpected = f"{env.__name__}.__init__() got an unexpected keyword argument 'odometry'"
        assert _error(env, odometry=True) == (TypeError, unexpected)
