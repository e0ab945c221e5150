"""``NomadOfficeMuJoCo-v0``: the stand-in robot on MuJoCo reads what the lattice simulator computes where it stands
on a lattice point, collides by contact and stays outside the wall, repeats seeded episodes exactly, and runs
any policy of ``NomadOffice-v0``'s spaces (issue 60's checks); its model files are its sensors' poses, its
``render()`` the MuJoCo scene, its lattice picture ``render_mode="lattice_rgb_array"``, and docs/mujoco.md's robot
loop ends at the time limit (issue 65, part 5)."""

from __future__ import annotations

import hashlib
import importlib.util
import re
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

if importlib.util.find_spec("mujoco") is None:
    pytest.skip("needs mujoco (the mujoco extra)", allow_module_level=True)

from stable_baselines3.common.vec_env import DummyVecEnv

import twodrl_envs  # noqa: F401
from tests.helpers.cloned_policy import cloned_model, reaches_goal
from twodrl_bench.trials import trial_outcomes
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, clearance, swept_clearance
from twodrl_envs.nomad.physics import ROBOT_MJCF, SENSOR_HEIGHT_CM, SPEED_CM_S, MuJoCoRobot, import_mujoco, office_model
from twodrl_envs.nomad.realistic import INCH_CM
from twodrl_envs.nomad.sensors import BEARINGS, HIGH_CM

mujoco = import_mujoco()  # as the env imports it (headless: MUJOCO_GL=egl unless set)
ROOT = Path(__file__).resolve().parents[2]
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
        (
            {"render_mode": "ansi"},
            ValueError,
            re.escape("render_mode must be None or one of ['rgb_array', 'lattice_rgb_array'], got 'ansi'"),
        ),
    ],
)
@pytest.mark.filterwarnings("ignore:.*not in the possible render_modes")  # gymnasium warns before we raise
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
    step_s = robot.mjmodel.opt.timestep
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    collisions = 0
    for _ in range(3000):
        _, _, terminated, truncated, info = env.step(int(rng.integers(4)))
        assert clearance(robot.position_cm()[None], walls)[0] > ROBOT_RADIUS_CM - SPEED_CM_S * step_s
        if info["collision"]:
            collisions += 1
            assert robot.contact
        if terminated or truncated:
            env.reset()
    assert collisions > 50


# --- the robot as a MuJoCo model (issue 65, part 5) ------------------------------------------------------------------


def _sensor_poses(xy_cm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The sensor model's origins (m, ``(16, 3)``) and axes ``(16, 3)`` of a robot at ``xy_cm``: sensor ``i`` on the
    body's surface at ``BEARINGS[i]`` (counter-clockwise from north), :data:`SENSOR_HEIGHT_CM` above the floor."""
    axes = np.stack([np.sin(BEARINGS), np.cos(BEARINGS), np.zeros(16)], axis=1)
    origins = np.concatenate([xy_cm + ROBOT_RADIUS_CM * axes[:, :2], np.full((16, 1), SENSOR_HEIGHT_CM)], axis=1)
    return origins / 100.0, axes


@pytest.mark.parametrize(
    "model_of",
    [
        lambda: mujoco.MjModel.from_xml_path(str(ROBOT_MJCF)),
        lambda: mujoco.MjModel.from_xml_path(str(ROBOT_MJCF.with_name("scene.xml"))),
        lambda: office_model(office_core("generated:S:3").office),
    ],
    ids=["robot file", "scene file", "env's model"],
)
def test_the_models_sites_are_the_sensor_models_poses(model_of) -> None:
    """Each of the 16 sonar and 16 IR sites sits where the sensor model measures from, its z axis the sensor's
    axis, wherever the robot stands: in the model file, in its scene and in the env's office."""
    model = model_of()
    data = mujoco.MjData(model)
    for xy in (np.zeros(2), np.array([123.4, -56.7])):
        data.qpos[:] = xy / 100.0
        mujoco.mj_kinematics(model, data)
        origins, axes = _sensor_poses(xy)
        for ring in ("sonar", "ir"):
            sites = [model.site(f"{ring}{i:02d}").id for i in range(16)]
            np.testing.assert_allclose(data.site_xpos[sites], origins, rtol=0, atol=1e-9)
            np.testing.assert_allclose(data.site_xmat[sites].reshape(16, 3, 3)[:, :, 2], axes, rtol=0, atol=1e-9)
    assert data.site_xpos[model.site("sonar04").id][0] < xy[0] / 100.0  # docs/nomad.md: sensor 4 looks west


def test_the_ir_rangefinders_read_the_envs_ideal_ir_ranges() -> None:
    """Switched on, the model's 16 IR rangefinders read what the env's artifact-free IR reads (one ray along each
    axis) at lattice cells of the paper's office."""
    core = office_core(None)
    robot = MuJoCoRobot(core, artifacts=False, heading_sd_rad=0.0)
    model = office_model(core.office)
    model.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
    data = mujoco.MjData(model)
    adr = model.sensor_adr[[model.sensor(f"ir{i:02d}").id for i in range(16)]]
    for cell in np.flatnonzero(core.lattice.reachable)[::25]:
        xy = core.lattice.cells[cell]
        data.qpos[:] = xy / 100.0
        mujoco.mj_forward(model, data)
        got = data.sensordata[adr] * 100.0
        np.testing.assert_allclose(np.where(got < 0, np.inf, got), robot.ideal_ranges(xy)[16:], rtol=0, atol=1e-6)


def _frames(render_mode: str, seed: int, actions: list[int]) -> list[np.ndarray]:
    """The env's frames after reset(seed) and after each action (resetting where an episode ends)."""
    env = gym.make(ID, render_mode=render_mode)
    env.reset(seed=seed)
    frames = [env.render()]
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        frames.append(env.render())
        if terminated or truncated:
            env.reset()
    env.close()
    return frames


def test_the_lattice_picture_under_its_new_name_is_the_old_render() -> None:
    """``render_mode="lattice_rgb_array"`` draws, frame for frame, what ``render()`` drew before the MuJoCo scene
    (the hash of the old code's frames on these seeded moves)."""
    actions = np.random.default_rng(1).integers(4, size=20).tolist()
    digest = hashlib.sha256(b"".join(frame.tobytes() for frame in _frames("lattice_rgb_array", 1, actions)))
    assert digest.hexdigest() == "42ddc8c84ea6a2afb2b8ebc2287a2bf354141ab0d8abe1d16d71939c54c4645c"


def test_render_draws_the_mujoco_scene_where_the_physics_has_the_robot() -> None:
    """``render()`` is MuJoCo's offscreen picture, of the lattice picture's size and unlike it, and the robot in it
    moves with the physics: after six moves north, the robot's colour is at its new pixel and gone from its old."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # the env's fallback where no OpenGL context can be made
        try:
            frames = _frames("rgb_array", 0, [0] * 6)
        except RuntimeWarning as warning:
            pytest.skip(f"no OpenGL back end for MuJoCo's offscreen rendering here: {warning}")
    lattice = _frames("lattice_rgb_array", 0, [0] * 6)
    for frame, picture in zip(frames, lattice, strict=True):
        assert frame.dtype == np.uint8 and frame.shape == picture.shape and frame.shape[2] == 3
        assert (frame != picture).any(axis=-1).mean() > 0.5
    env = gym.make(ID).unwrapped
    x0, _, _, y1 = env.core.office.bounds
    start = np.array(env.core.office.start)

    def pixel(frame: np.ndarray, xy: np.ndarray) -> np.ndarray:  # 15 cm east of the robot's centre: its body
        col, row = round((xy[0] + 15.0 - x0) * 1.5 + 8), round((y1 - xy[1]) * 1.5 + 8)
        return frame[row, col].astype(int)

    moved = start + np.array([0.0, 60.0])
    assert np.abs(pixel(frames[-1], moved) - pixel(frames[0], start)).max() <= 8
    assert np.abs(pixel(frames[-1], start) - pixel(frames[0], start)).max() > 40


def docs_robot_loop() -> str:
    """docs/mujoco.md's robot loop (the python block of "The robot loop without a robot")."""
    text = (ROOT / "docs" / "mujoco.md").read_text()
    section = text[text.index("## The robot loop without a robot") :]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


def _shuttling_policy(path: Path, turn_y_cm: float) -> None:
    """An ONNX policy as ``sb3-twodrl-export --input-stage`` writes one (input ``obs``: the (n, 34) cm readings
    and odometry, float64; output ``action``, (n,)) that moves north below ``turn_y_cm`` of odometry and south above it:
    it shuttles between two cells, reaching neither the goal nor a wall."""
    import onnx
    from onnx import TensorProto, helper

    nodes = [
        helper.make_node("Gather", ["obs", "y_index"], ["y"], axis=1),
        helper.make_node("Less", ["y", "turn"], ["below"]),
        helper.make_node("Where", ["below", "north", "south"], ["action"]),
    ]
    constants = [
        helper.make_tensor("y_index", TensorProto.INT64, [], [33]),
        helper.make_tensor("turn", TensorProto.DOUBLE, [], [turn_y_cm]),
        helper.make_tensor("north", TensorProto.INT64, [], [0]),
        helper.make_tensor("south", TensorProto.INT64, [], [2]),
    ]
    graph = helper.make_graph(
        nodes,
        "shuttle",
        [helper.make_tensor_value_info("obs", TensorProto.DOUBLE, ["n", 34])],
        [helper.make_tensor_value_info("action", TensorProto.INT64, ["n"])],
        constants,
    )
    onnx.save(helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)]), str(path))


def test_the_docs_robot_loop_runs_as_written_and_stops_at_the_time_limit(tmp_path: Path) -> None:
    """docs/mujoco.md's loop, as written, with a policy that never reaches the goal: it ends after the env's time
    limit (the map's test time limit) instead of a ``RuntimeError``."""
    pytest.importorskip("onnxruntime")
    pytest.importorskip("onnx")
    from twodrl_envs.nomad.drive import StandInRobot

    office = ROOT / "envs" / "twodrl_envs" / "nomad" / "maps" / "office.json"
    (tmp_path / "my_office.json").write_text(office.read_text())
    _shuttling_policy(tmp_path / "policy.onnx", office_core(None).office.start[1] + 5.0)
    out = subprocess.run(
        [sys.executable, "-c", docs_robot_loop()], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr[-3000:]
    limit = StandInRobot(ID, map=str(tmp_path / "my_office.json")).time_limit
    assert out.stdout.strip().splitlines()[-1] == f"{limit} moves: the time limit"
