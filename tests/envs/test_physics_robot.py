"""``NomadOfficeMuJoCo-v0``: the stand-in robot on MuJoCo reads what the lattice simulator computes where it stands
on a lattice point, collides by contact and stays outside the wall, repeats seeded episodes exactly, and runs
any policy of ``NomadOffice-v0``'s spaces (issue 60's checks)."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("mujoco")

from stable_baselines3.common.vec_env import DummyVecEnv

import twodrl_envs  # noqa: F401
from tests.cloned_policy import cloned_model, reaches_goal
from twodrl_bench.trials import trial_outcomes
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, clearance, swept_clearance
from twodrl_envs.nomad.physics import SPEED_CM_S, TIMESTEP_S, MuJoCoRobot
from twodrl_envs.nomad.realistic import INCH_CM
from twodrl_envs.nomad.sensors import BEARINGS, HIGH_CM

ID = "NomadOfficeMuJoCo-v0"


def _axis_through_a_wall_end(office_walls: np.ndarray, origin: np.ndarray, bearing: float) -> bool:
    """Whether a ray from ``origin`` along ``bearing`` passes exactly through a wall's end point: there the lattice
    simulator's single ray slips past the wall (seen edge-on, or through a vertex), a ray in MuJoCo hits its end."""
    axis = np.array([np.sin(bearing), np.cos(bearing)])
    ends = np.concatenate([office_walls[:, :2], office_walls[:, 2:]]) - origin
    across = np.abs(ends[:, 0] * axis[1] - ends[:, 1] * axis[0])
    return bool(np.any((across < 1e-6) & (ends @ axis > 0)))


@pytest.mark.parametrize("map_name", [None, "generated:S:3", "generated:M:5", "corridor"])
def test_ideal_readings_at_lattice_points_equal_the_exact_ranges(map_name: str | None) -> None:
    """At every reachable lattice point, the artifact-free ray casts equal ``sensors.exact_ranges`` (saturated):
    sonar within the sonar's resolution (an inch), IR within 0.05 cm, except an IR axis through a wall's end."""
    core = office_core(map_name)
    robot = MuJoCoRobot(core, artifacts=False, heading_sd_rad=0.0)
    cells = np.flatnonzero(core.lattice.reachable)
    got = np.minimum(np.array([robot.ideal_ranges(core.lattice.cells[c]) for c in cells]), HIGH_CM)
    exact = np.minimum(core.ranges[cells], HIGH_CM)
    assert np.abs(got[:, :16] - exact[:, :16]).max() <= INCH_CM
    edge_on = 0  # IR readings that differ where the axis passes through a wall's end
    for row, cell in enumerate(cells):
        for sensor in range(16):
            origin = core.lattice.cells[cell] + ROBOT_RADIUS_CM * np.array(
                [np.sin(BEARINGS[sensor]), np.cos(BEARINGS[sensor])]
            )
            if _axis_through_a_wall_end(core.office.walls, origin, BEARINGS[sensor]):
                edge_on += abs(got[row, 16 + sensor] - exact[row, 16 + sensor]) > 0.05
                assert got[row, 16 + sensor] <= exact[row, 16 + sensor] + 0.05  # MuJoCo sees the end, nearer
            else:
                assert abs(got[row, 16 + sensor] - exact[row, 16 + sensor]) <= 0.05, (cell, sensor)
    assert edge_on < 0.01 * got[:, 16:].size


def test_the_spaces_are_nomad_offices() -> None:
    env, ideal = gym.make(ID), gym.make("NomadOffice-v0")
    assert env.observation_space == ideal.observation_space and env.action_space == ideal.action_space
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and set(info) == set(ideal.reset(seed=0)[1])
    assert gym.spec(ID).max_episode_steps == gym.spec("NomadOffice-v0").max_episode_steps


def test_a_move_into_a_wall_is_a_collision_and_the_robot_stays_outside() -> None:
    env = gym.make(ID)
    env.reset(seed=0)
    robot = env.unwrapped.robot
    walls = env.unwrapped.core.office.walls
    for _ in range(100):  # west until the wall
        before = env.unwrapped._pos.copy()
        _, reward, terminated, _, info = env.step(3)
        if info["collision"]:
            break
        assert not robot.contact and abs(info["position_cm"][0] - before[0] + 10.0) < 0.1
    assert info["collision"] and terminated and reward == -1.0 and robot.contact
    assert info["position_cm"] == tuple(before)  # the core's rule: a collision leaves the robot where it was
    assert clearance(np.array([before]), walls)[0] > ROBOT_RADIUS_CM
    touched = robot.position_cm()
    assert clearance(touched[None], walls)[0] > ROBOT_RADIUS_CM - 0.5  # MuJoCo's robot is stopped at the wall
    assert touched[0] < before[0]  # ... after moving towards it


def test_collisions_are_the_lattices_where_the_robot_keeps_to_the_lattice() -> None:
    """Ideal robot (no odometry error, no turret error): the moves' collisions are the lattice move table's, where
    the lattice's move clears a wall by more than the robot's drift off the lattice (0.5 cm) or hits it."""
    env = gym.make(ID, artifacts=False, heading_sd_rad=0.0).unwrapped
    lattice = env.core.lattice
    rng = np.random.default_rng(3)
    env.reset(seed=3)
    collisions = 0
    for _ in range(150):
        origin = np.array(lattice.origin)
        cell = lattice.index(origin + np.round((env._pos - origin) / 10.0) * 10.0)
        action = int(rng.integers(4))
        here = lattice.cells[cell]
        gap = swept_clearance(here[None], (here + MOVES_CM[action])[None], env.core.office.walls)[0]
        _, _, terminated, truncated, info = env.step(action)
        if cell >= 0 and abs(gap - ROBOT_RADIUS_CM) > 0.5:  # (the drift may end a move within 0.5 cm of a wall)
            assert info["collision"] == (lattice.moves[cell, action] < 0)
        collisions += info["collision"]
        if terminated or truncated:
            env.reset()
    assert collisions > 3


def test_seeded_episodes_repeat_exactly() -> None:
    actions = np.random.default_rng(0).integers(4, size=40).tolist()

    def episode(env: gym.Env, seed: int) -> list[np.ndarray]:
        obs, _ = env.reset(seed=seed)
        out = [obs]
        for action in actions:
            obs, reward, terminated, truncated, info = env.step(action)
            out += [obs, np.array([reward, *info["position_cm"]])]
            if terminated or truncated:
                break
        return out

    first, second = gym.make(ID), gym.make(ID)
    one = episode(first, 11)
    episode(second, 5)  # another episode in between: the physics state must not leak into the next
    for a, b in zip(one, episode(second, 11), strict=True):
        np.testing.assert_array_equal(a, b)
    other = episode(gym.make(ID), 12)
    assert not all(np.array_equal(a, b) for a, b in zip(one, other, strict=False))


def test_odometry_is_dead_reckoning_of_the_measured_motion() -> None:
    """Free moves end about 10 cm on; the odometry reads the joints' motion, misread by the stand-in's motion
    error (artifacts), or exactly (``artifacts=False``)."""
    for artifacts in (False, True):
        env = gym.make(ID, artifacts=artifacts).unwrapped
        obs, _ = env.reset(seed=2)
        start = env._pos.copy()
        for _ in range(3):
            obs, _, _, _, info = env.step(0)
            assert not info["collision"]
        true = np.array(info["position_cm"])
        assert abs(true[1] - start[1] - 30.0) < 0.3 and abs(true[0] - start[0]) < 1e-6
        odometry = env.core.odometry(env._odo)
        np.testing.assert_array_equal(obs[-2:], odometry)
        error = np.abs(env._odo - true).max()
        assert error < 1e-9 if not artifacts else 0.01 < error < 5.0


def test_a_policy_that_reaches_the_goal_runs_and_its_trials_repeat() -> None:
    model = cloned_model(None)
    assert reaches_goal(model, "NomadOffice-v0", None)

    def trials() -> list[str]:
        venv = DummyVecEnv([lambda: gym.make(ID)] * 3)
        try:
            return trial_outcomes(model, venv, seed=7)
        finally:
            venv.close()

    outcomes = trials()
    assert set(outcomes) <= {"shortcut", "detour", "collision", "timeout"}
    assert trials() == outcomes


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"heading_sd_rad": -0.1}, ValueError, "heading_sd_rad must be a finite number >= 0, got -0.1"),
        ({"artifacts": "yes"}, TypeError, "artifacts must be a bool, got str: 'yes'"),
        ({"model": "realistic"}, TypeError, "model must be a RealisticModel or None, got str"),
        ({"observation": "cell"}, ValueError, "observation='cell' needs a robot that moves on the lattice"),
        ({"progress": 0.05}, ValueError, "progress=0.05 needs a robot that moves on the lattice"),
    ],
)
def test_bad_options_are_errors_naming_them(options: dict, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        gym.make(ID, **options)


def test_without_mujoco_the_error_names_the_extra() -> None:
    code = (
        "import sys; sys.modules['mujoco'] = None\n"
        "import gymnasium as gym, twodrl_envs\n"
        "try:\n    gym.make('NomadOfficeMuJoCo-v0')\n"
        "except ModuleNotFoundError as err:\n    print(err)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert 'pip install "sb3-twodrl[mujoco]"' in out.stdout


def test_importing_the_env_package_imports_neither_mujoco_nor_rosbags() -> None:
    code = (
        "import sys, gymnasium as gym, twodrl_envs, twodrl_envs.nomad.physics, twodrl_envs.analysis.cli\n"
        "gym.make('NomadOffice-v0')\n"
        "print(sorted(m for m in ('mujoco', 'rosbags') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_policys_trials_on_both_stand_ins_are_counted_and_repeat() -> None:
    from twodrl_bench.stand_ins import stand_in_trials

    model = cloned_model(None)
    counts = stand_in_trials(model, 2, seed=3)
    assert set(counts) == {"NomadOfficeMuJoCo-v0", "NomadOfficeReal-v0"}
    for tallies in counts.values():
        assert tallies["success"] + tallies["collision"] + tallies["timeout"] == 2
    assert stand_in_trials(model, 2, seed=3) == counts
    with pytest.raises(ValueError, match=r"n must be a positive int, got 0"):
        stand_in_trials(model, 0)


@pytest.mark.slow
def test_a_long_drive_never_enters_a_wall_and_collides_only_by_contact() -> None:
    """3,000 random moves over a generated office: the robot's centre never comes nearer a wall than its radius less
    one physics step's travel (the depth at which the contact is found), and every collision the env reports is a
    contact in MuJoCo."""
    env = gym.make(ID, map="generated:M:5")
    robot, walls = env.unwrapped.robot, env.unwrapped.core.office.walls
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    collisions = 0
    for _ in range(3000):
        _, _, terminated, truncated, info = env.step(int(rng.integers(4)))
        assert clearance(robot.position_cm()[None], walls)[0] > ROBOT_RADIUS_CM - SPEED_CM_S * TIMESTEP_S
        if info["collision"]:
            collisions += 1
            assert robot.contact
        if terminated or truncated:
            env.reset()
    assert collisions > 50
