"""A stand-in Nomad 200 on the MuJoCo physics engine (``NomadOfficeMuJoCo-v0``, extra ``sb3-twodrl[mujoco]``).

The office's rules (eq. 11-12, goal, route, spaces) are :mod:`twodrl_envs.nomad.core`'s; this module is a
:class:`~twodrl_envs.nomad.core.Robot` whose motion and readings come from a MuJoCo model built from the map:

* **scene**: each wall segment (obstacle edges included) a box 1 m high and 0.2 mm thick on a floor, which the
  sensors' rays hit; a horizontal capsule of radius :data:`SKIN_CM` along each segment is its contact skin;
* **robot**: the model file :data:`ROBOT_MJCF` (``robots/nomad200/``, its numbers and their sources in the
  folder's README), included in the office's scene: a 60 cm cylinder of 60 kg on two slide joints (a synchro drive
  translates and keeps the heading north; no turning joint), driven by a velocity actuator per axis whose force
  limit caps the acceleration; its contact cylinder is :data:`SKIN_CM` thinner than the body, so it touches a skin
  exactly when its centre comes within 30 cm of the wall's segment: the lattice simulator's disc rule. A site marks
  each sensor's pose, and a MuJoCo ``rangefinder`` each IR beam (switched off in the env, which casts its own
  rays: ``mjDSBL_SENSOR``);
* **a move**: the velocity command for the time 10 cm takes at :data:`SPEED_CM_S`, then a stop command until the
  robot has settled; momentum and contact decide where it ends. A contact during the move is a collision: the
  move ends there and the robot stays outside the wall;
* **odometry**: dead reckoning from the slide joints' measured motion, misread by the stand-in robot's motion
  error of the same move (:meth:`~twodrl_envs.nomad.realistic.RealisticModel.displacement` minus the command:
  its per-episode scale and misalignment and per-move slip), so the drift is ``NomadOfficeReal-v0``'s;
* **readings**: ray casts (``mj_multiRay``) from the turret, sensor ``i`` on the body surface at the bearing of
  :mod:`twodrl_envs.nomad.sensors`. Ideal (``artifacts=False``): each sonar the nearest hit of a fan of
  :data:`CONE_RAYS` rays over its 22.5 degree cone, each IR the hit along its axis. With artifacts (default), the
  fan of the :class:`~twodrl_envs.nomad.realistic.RealisticModel`'s beam, where a ray cast carries them: a ray
  returns only from a wall it meets within the wall surface's critical angle, concave corners echo
  (:class:`~twodrl_envs.nomad.realistic.Scene`), echoes inside the blanking distance are unheard, the IR
  intensity depends on reflectance and incidence, then the model's per-ping noise, drop-outs and inch
  resolution (:meth:`~twodrl_envs.nomad.realistic.Scene.ranges`). Multipath and cross-talk (rays followed
  through reflections) are not cast. The turret's heading is off north by a per-episode angle of sd
  ``heading_sd_rad``.

Every draw is counter-based from (episode key, step) and MuJoCo is deterministic, so a seed gives one episode.
``mujoco`` is imported when a robot is built, not when :mod:`twodrl_envs` is.

``render()`` (``render_mode="rgb_array"``) draws the MuJoCo scene from above with ``mujoco.Renderer``, offscreen
(:class:`TopDownView`); ``render_mode="lattice_rgb_array"`` draws the lattice picture of the other Nomad IDs.
"""

from __future__ import annotations

import itertools
import os
import sys
import warnings
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import OfficeCore, Robot, counter_word
from twodrl_envs.nomad.episode import non_negative
from twodrl_envs.nomad.geometry import MOVES_CM, REGION_KEYS, ROBOT_RADIUS_CM, STEP_CM, OfficeMap
from twodrl_envs.nomad.office import NomadOfficeEnv
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import BEARINGS, N_SONAR, SONAR_HALF_ANGLE, SONAR_MAX_CM

ROBOT_MJCF = Path(__file__).with_name("robots") / "nomad200" / "nomad200.xml"
"""The robot's MuJoCo model (body, mass, drive, time step, sensor sites, IR rangefinders); the numbers and where
they come from: the folder's README.md. ``scene.xml`` beside it puts the robot on a floor by a wall corner."""
SPEED_CM_S = 25.0
"""Commanded speed of a move: half the Nomad 200's top speed (20 in/s), for 10 cm moves."""
SETTLED_CM_S = 0.1
"""A move ends when the robot is slower than this after the stop command (or :data:`MAX_SETTLE_S` has passed)."""
MAX_SETTLE_S = 1.0
WALL_HEIGHT_CM = 100.0
SENSOR_HEIGHT_CM = 60.0
"""Height of both sensor rings (the model's sites, tested equal)."""
SKIN_CM = 5.0
"""Radius of the walls' contact capsules; the robot's contact cylinder is this much thinner than its body."""
CONE_RAYS = 9
"""Rays over each ideal sonar cone (both edges and the axis): at most 0.06% longer than the cone's nearest point
on a wall seen across it."""
PIXELS_PER_CM, MARGIN_PX = 1.5, 8
"""Scale and margin of :meth:`NomadOfficeMuJoCoEnv.render`'s frames: the lattice picture's, so both are one size."""
RENDER_MODES = ("rgb_array", "lattice_rgb_array")
TRAIL = np.array([0.86, 0.24, 0.24, 1.0], dtype=np.float32)
"""Colour of the robot's trail in :class:`TopDownView`'s frames (the lattice picture's)."""
_CUTOFF_CM = 2000.0
_HEADING_SALT = 0x2545F4914F6CDD1D
MUJOCO_HINT = 'NomadOfficeMuJoCo-v0 needs the MuJoCo physics engine: pip install "sb3-twodrl[mujoco]"'
GL_PACKAGES = "EGL: apt-get install libegl1 libgl1-mesa-dri; OSMesa: apt-get install libosmesa6"
"""The Debian packages of MuJoCo's headless OpenGL back ends (``MUJOCO_GL=egl`` or ``osmesa``)."""


def import_mujoco() -> Any:
    """The ``mujoco`` module, or ``ModuleNotFoundError`` saying which extra installs it.

    Imported first here on Linux without a display and without ``MUJOCO_GL``, it renders through EGL
    (``MUJOCO_GL=egl``, headless); MuJoCo's default there, GLFW, needs a display."""
    headless = sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if headless and "mujoco" not in sys.modules:
        os.environ.setdefault("MUJOCO_GL", "egl")
    try:
        import mujoco
    except ImportError as err:
        raise ModuleNotFoundError(f"{MUJOCO_HINT} ({err})", name="mujoco") from err
    except Exception as err:  # MUJOCO_GL names a back end whose library is missing: mujoco fails as it imports
        raise ImportError(
            f"mujoco cannot be imported with MUJOCO_GL={os.environ.get('MUJOCO_GL')!r} ({type(err).__name__}: {err}):"
            f" install that OpenGL back end ({GL_PACKAGES}) or unset MUJOCO_GL"
        ) from err
    return mujoco


def _m(cm: float) -> str:
    return f"{cm / 100.0:.6f}"


def office_mjcf(office: OfficeMap) -> str:
    """The MJCF text of ``office``'s scene (module docstring), the robot included as ``nomad200.xml``
    (:data:`ROBOT_MJCF`: :func:`office_model` compiles it); lengths in metres, x east, y north."""
    x0, y0, x1, y1 = office.bounds
    half_height = WALL_HEIGHT_CM / 2
    walls, skins = [], []
    for i, (ax, ay, bx, by) in enumerate(office.walls):
        length = float(np.hypot(bx - ax, by - ay))
        angle = float(np.arctan2(by - ay, bx - ax))
        walls.append(
            f'<geom name="wall{i}" type="box" group="0" pos="{_m((ax + bx) / 2)} {_m((ay + by) / 2)} {_m(half_height)}"'
            f' size="{_m(length / 2 + 0.01)} 0.0001 {_m(half_height)}" euler="0 0 {angle:.9f}" rgba=".35 .35 .4 1"/>'
        )
        z = _m(SENSOR_HEIGHT_CM / 2)
        skins.append(
            f'<geom name="skin{i}" type="capsule" group="3" conaffinity="1" size="{_m(SKIN_CM)}"'
            f' fromto="{_m(ax)} {_m(ay)} {z} {_m(bx)} {_m(by)} {z}" rgba=".25 .25 .3 1"/>'
        )
    regions = []
    for name, rgba in zip(REGION_KEYS, (".2 .75 .3 .6", ".95 .75 .2 .35", ".3 .5 .95 .35"), strict=True):
        if name in office.regions:
            rx0, ry0, rx1, ry1 = office.regions[name]
            regions.append(
                f'<geom name="{name}" type="box" group="2" pos="{_m((rx0 + rx1) / 2)} {_m((ry0 + ry1) / 2)} 0.001"'
                f' size="{_m((rx1 - rx0) / 2)} {_m((ry1 - ry0) / 2)} 0.001" rgba="{rgba}"/>'
            )
    return f"""<mujoco model="{office.name}">
  <compiler angle="radian"/>
  <default><geom contype="0" conaffinity="0" friction="0.5 0.005 0.0001"/></default>
  <worldbody>
    <light pos="{_m((x0 + x1) / 2)} {_m((y0 + y1) / 2)} 5" dir="0 0 -1" directional="true"/>
    <geom name="floor" type="plane" group="2" pos="{_m((x0 + x1) / 2)} {_m((y0 + y1) / 2)} 0"
      size="{_m((x1 - x0) / 2 + 50)} {_m((y1 - y0) / 2 + 50)} 0.1" rgba=".92 .9 .85 1"/>
    {"".join(regions)}
    {"".join(walls)}
    {"".join(skins)}
  </worldbody>
  <include file="{ROBOT_MJCF.name}"/>
</mujoco>
"""


def office_model(office: OfficeMap) -> Any:
    """The compiled ``mujoco.MjModel`` of :func:`office_mjcf`, the robot read from :data:`ROBOT_MJCF`; its
    rangefinders switched off (``mjDSBL_SENSOR``: the env casts its own rays)."""
    mujoco = import_mujoco()
    model = mujoco.MjModel.from_xml_string(office_mjcf(office), {ROBOT_MJCF.name: ROBOT_MJCF.read_bytes()})
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_SENSOR
    return model


def _fan(half_angle: float, rays: int) -> np.ndarray:
    """Ray offsets (radians) of a fan over a cone of ``half_angle``: ``rays`` evenly spaced, edges included."""
    return np.linspace(-half_angle, half_angle, rays) if rays > 1 else np.zeros(1)


class MuJoCoRobot(Robot):
    """The Nomad 200 on MuJoCo (module docstring): one robot, always off the lattice.

    ``model`` (default :class:`~twodrl_envs.nomad.realistic.RealisticModel`) gives the sensor artifacts and the
    odometry error; ``artifacts=False`` reads ideal ray-cast ranges and exact odometry; ``heading_sd_rad`` is
    the sd of the turret's per-episode heading error. The env places the robot (:meth:`place`) before each
    move; :meth:`displacement` runs the move and keeps its odometry in :attr:`odometry_cm` (the measured
    displacement as the encoders report it) and whether it touched a wall in :attr:`contact`.
    """

    on_lattice = False

    def __init__(
        self,
        core: OfficeCore,
        model: RealisticModel | None = None,
        *,
        artifacts: bool = True,
        heading_sd_rad: float = 0.01,
    ) -> None:
        if model is not None and not isinstance(model, RealisticModel):
            raise TypeError(f"model must be a RealisticModel or None, got {type(model).__name__}: {model!r}")
        if not isinstance(artifacts, bool):
            raise TypeError(f"artifacts must be a bool, got {type(artifacts).__name__}: {artifacts!r}")
        super().__init__(core)
        self.model = RealisticModel() if model is None else model
        self.artifacts = artifacts
        self.heading_sd_rad = non_negative("heading_sd_rad", heading_sd_rad)
        mujoco = import_mujoco()
        self._mj = mujoco
        self.mjmodel = office_model(core.office)
        self.data = mujoco.MjData(self.mjmodel)
        mujoco.mj_forward(self.mjmodel, self.data)
        self._body = self.mjmodel.body("robot").id
        first = self.mjmodel.geom("wall0").id
        self._wall_of_geom = np.full(self.mjmodel.ngeom + 1, -1, dtype=np.intp)  # geom id -1 (no hit) -> -1
        self._wall_of_geom[first : first + len(core.office.walls)] = np.arange(len(core.office.walls))
        self._groups = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # rays see the walls' boxes only
        timestep = float(self.mjmodel.opt.timestep)
        self._drive_steps = round(STEP_CM / SPEED_CM_S / timestep)
        self._settle_steps = round(MAX_SETTLE_S / timestep)
        self._xy = np.array(core.office.start, dtype=np.float64)
        self.contact = False
        self.odometry_cm = np.zeros(2)

    @cached_property
    def scene(self) -> Any:
        """The :class:`~twodrl_envs.nomad.realistic.Scene` of the model (wall materials, beam fan, corners)."""
        return self.model.scene(self.core.office)

    # --- motion -------------------------------------------------------------------------------
    def reset_motion(self, xy: np.ndarray) -> None:
        """Start an episode: the robot at rest at ``xy`` (cm), the solver's warm start cleared."""
        self._mj.mj_resetData(self.mjmodel, self.data)
        self._set(xy)
        self._mj.mj_forward(self.mjmodel, self.data)  # the walls' poses, which the rays read

    def _set(self, xy: np.ndarray) -> None:
        self.data.qpos[:] = np.asarray(xy, dtype=np.float64) / 100.0
        self.data.qvel[:] = 0.0
        self.data.ctrl[:] = 0.0
        self._xy = np.asarray(xy, dtype=np.float64).copy()

    def place(self, xy: np.ndarray) -> None:
        """Make ``xy`` (cm) the start of the next move; the robot keeps its motion unless it is elsewhere."""
        if not np.allclose(self.position_cm(), xy, rtol=0.0, atol=1e-6):
            self._set(xy)
        self._xy = np.asarray(xy, dtype=np.float64).copy()

    def position_cm(self) -> np.ndarray:
        """The robot's centre (cm) in MuJoCo now."""
        return self.data.qpos * 100.0

    def _run(self, steps: int, stop_when_settled: bool) -> np.ndarray | None:
        """Step the physics; the robot's position (m, joint coordinates) where it first touched a wall (it stays
        there), else None. ``mj_step1`` + ``mj_step2`` is ``mj_step``, split where the contacts are known."""
        mujoco, m, d = self._mj, self.mjmodel, self.data
        settled = (SETTLED_CM_S / 100.0) ** 2
        for _ in range(steps):
            mujoco.mj_step1(m, d)  # positions, collisions
            if d.ncon:  # only the robot can touch anything
                return d.qpos.copy()
            mujoco.mj_step2(m, d)  # forces, integration
            if stop_when_settled and d.qvel[0] ** 2 + d.qvel[1] ** 2 < settled:
                break
        return None

    def move(self, action: int) -> np.ndarray:
        """Drive one commanded 10 cm move from where the robot is; its true displacement (cm) and :attr:`contact`.

        On a contact the move ends (the bumper stops the robot) and the displacement is to where it touched.
        """
        start = self.data.qpos.copy()
        direction = MOVES_CM[action] / STEP_CM
        self.data.ctrl[:] = direction * SPEED_CM_S / 100.0
        touched = self._run(self._drive_steps, stop_when_settled=False)
        self.data.ctrl[:] = 0.0
        if touched is None:
            touched = self._run(self._settle_steps, stop_when_settled=True)
        self.contact = touched is not None
        if self.contact:
            self.data.qvel[:] = 0.0
        end = self.data.qpos if touched is None else touched
        return (end - start) * 100.0

    def displacement(self, actions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """The physics' true displacement ``(1, 2)`` cm of one commanded move from :meth:`place`'s position."""
        if len(actions) != 1:
            raise ValueError(f"MuJoCoRobot moves one robot, got {len(actions)} actions")
        self._set_if_elsewhere()
        true = self.move(int(actions[0]))
        if self.artifacts:
            error = self.model.displacement(actions, keys, steps)[0] - MOVES_CM[int(actions[0])]
            self.odometry_cm = true - error
        else:
            self.odometry_cm = true.copy()
        return true[None]

    def _set_if_elsewhere(self) -> None:
        if not np.allclose(self.position_cm(), self._xy, rtol=0.0, atol=1e-6):
            self._set(self._xy)

    # --- readings -----------------------------------------------------------------------------
    def heading(self, key: int) -> float:
        """The turret's heading error (radians, counter-clockwise) in the episode of noise key ``key``."""
        if self.heading_sd_rad == 0.0:
            return 0.0
        lane = np.array([counter_word(int(key) ^ _HEADING_SALT, 0) & 0xFFFF])
        return float(self.heading_sd_rad * sensors.standard_normal(lane)[0])

    def cast(
        self, xy: np.ndarray, offsets: list[np.ndarray] | np.ndarray, heading: float = 0.0
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Ranges (cm, ``inf``: no hit) and wall indices (-1: none) of rays from the 16 sensors at centre ``xy``
        (cm): sensor ``s`` casts ``offsets[s]`` (radians clockwise from its bearing), the turret turned
        ``heading`` radians counter-clockwise. One list entry per sensor."""
        mujoco, m, d = self._mj, self.mjmodel, self.data
        bearings = BEARINGS - heading
        counts = [len(o) for o in offsets]
        ends = np.cumsum(counts)
        angles = np.repeat(bearings, counts) + np.concatenate(list(offsets))
        dirs = np.zeros((len(angles), 3))
        dirs[:, 0], dirs[:, 1] = np.sin(angles), np.cos(angles)
        origins = np.empty((N_SONAR, 3))
        origins[:, 0] = (xy[0] + ROBOT_RADIUS_CM * np.sin(bearings)) / 100.0
        origins[:, 1] = (xy[1] + ROBOT_RADIUS_CM * np.cos(bearings)) / 100.0
        origins[:, 2] = SENSOR_HEIGHT_CM / 100.0
        dist = np.empty(len(angles))
        geom = np.empty(len(angles), dtype=np.int32)
        flat = dirs.ravel()
        for s, (start, end) in enumerate(zip(ends - counts, ends, strict=True)):
            mujoco.mj_multiRay(
                m, d, origins[s], flat[3 * start : 3 * end], self._groups, 1, self._body,
                geom[start:end], dist[start:end], None, end - start, _CUTOFF_CM / 100,
            )  # fmt: skip
        hit = dist >= 0.0
        ranges = np.where(hit, dist * 100.0, np.inf)
        walls = np.where(hit, self._wall_of_geom[geom], -1)
        return np.split(ranges, ends[:-1]), np.split(walls, ends[:-1])

    def cone_offsets(self, xy: np.ndarray, heading: float = 0.0) -> list[np.ndarray]:
        """Per sensor, the ray offsets (radians) of its ideal sonar cone: a fan of :data:`CONE_RAYS` rays (the axis
        the middle one) and a ray at each wall end and each wall's nearest point that lies inside the cone, so
        that the nearest hit is the cone's nearest wall point (:func:`~twodrl_envs.nomad.geometry.cone_ranges`)."""
        walls = self.core.office.walls
        bearings = BEARINGS - heading
        axes = np.stack([np.sin(bearings), np.cos(bearings)], axis=1)
        origins = np.asarray(xy, dtype=np.float64) + ROBOT_RADIUS_CM * axes  # (16, 2)
        a, e = walls[:, :2], walls[:, 2:] - walls[:, :2]
        t = np.clip(np.einsum("swk,wk->sw", origins[:, None, :] - a, e) / np.einsum("wk,wk->w", e, e), 0.0, 1.0)
        points = np.concatenate(
            [a + t[..., None] * e, np.broadcast_to(a, (16, *a.shape)), np.broadcast_to(walls[:, 2:], (16, *a.shape))],
            axis=1,
        )
        vec = points - origins[:, None, :]
        offset = np.arctan2(vec[..., 0], vec[..., 1]) - bearings[:, None]
        offset = (offset + np.pi) % (2 * np.pi) - np.pi
        fan = _fan(SONAR_HALF_ANGLE, CONE_RAYS)
        return [np.concatenate([fan, row[np.abs(row) <= SONAR_HALF_ANGLE]]) for row in offset]

    def ideal_ranges(self, xy: np.ndarray, heading: float = 0.0) -> np.ndarray:
        """Artifact-free ranges ``(32,)`` cm at centre ``xy``: each sonar the nearest hit in its cone
        (:meth:`cone_offsets`), each IR the hit along its axis."""
        ranges, _ = self.cast(xy, self.cone_offsets(xy, heading), heading)
        return np.array([r.min() for r in ranges] + [r[CONE_RAYS // 2] for r in ranges])

    def ranges(self, xy: np.ndarray, key: int, step: int) -> np.ndarray:
        """Readings ``(32,)`` cm at centre ``xy`` as the robot reports them (module docstring)."""
        heading = self.heading(key)
        if not self.artifacts:
            return self.ideal_ranges(xy, heading)
        scene, model = self.scene, self.model
        fan = _fan(np.deg2rad(model.beam_half_angle_deg), model.rays_per_beam)
        with_axis = np.concatenate([fan, [0.0]])
        cast, walls = self.cast(xy, [with_axis] * N_SONAR, heading)
        t, wall = np.array(cast), np.array(walls)
        bearings = BEARINGS - heading
        angles = bearings[:, None] + with_axis[None, :]
        dirs = np.stack([np.sin(angles), np.cos(angles)], axis=-1)
        normals = scene.normal[np.maximum(wall, 0)]
        cos_inc = np.abs(np.einsum("...k,...k->...", dirs, normals))
        diffuse = (wall >= 0) & (cos_inc >= scene.cos_critical[np.maximum(wall, 0)])
        positions = np.asarray(xy, dtype=np.float64)[None]
        own = np.minimum(np.where(diffuse[:, :-1], t[:, :-1], np.inf).min(axis=1), scene._corner_echoes(positions)[0])
        own = np.where((own >= model.blank_cm) & (own <= SONAR_MAX_CM), own, np.inf)
        ir_range = t[:, -1]
        ir_gain = np.where(wall[:, -1] >= 0, scene.reflectance[np.maximum(wall[:, -1], 0)] * cos_inc[:, -1], 0.0)
        cached = (own[None], np.full((1, N_SONAR), np.inf), ir_range[None], ir_gain[None])
        keys, steps = np.array([key], dtype=np.uint64), np.array([step], dtype=np.int64)
        return scene.ranges(positions, keys, steps, cached)[0]

    def pose_readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        rows = [self.ranges(xy, int(key), int(step)) for xy, key, step in zip(positions, keys, steps, strict=True)]
        return sensors.normalise(np.array(rows).reshape(-1, sensors.N_READINGS))


class TopDownView:
    """The MuJoCo scene of a :class:`MuJoCoRobot` seen from above, offscreen (``mujoco.Renderer``): the office's
    walls (their contact skins, which show from above), route regions and goal on the floor, the robot (its
    turret, the sensor sites on its rim) where the physics has it, and its trail.

    Needs an OpenGL context without a display (:func:`import_mujoco` picks ``MUJOCO_GL=egl``); where none can be
    made, building the view raises MuJoCo's error.
    """

    def __init__(self, robot: MuJoCoRobot) -> None:
        mujoco, model = robot._mj, robot.mjmodel
        x0, y0, x1, y1 = robot.core.office.bounds
        width, height = (round(span * PIXELS_PER_CM) + 2 * MARGIN_PX for span in (x1 - x0, y1 - y0))
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        model.vis.global_.fovy = height / PIXELS_PER_CM / 100.0  # orthographic: the view's height in metres
        self.renderer = mujoco.Renderer(model, height, width)
        self.renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0  # none seen from above; 2.5 times the speed
        self.camera = mujoco.MjvCamera()
        self.camera.orthographic = 1
        self.camera.lookat[:] = ((x0 + x1) / 200.0, (y0 + y1) / 200.0, 0.0)
        self.camera.distance, self.camera.elevation, self.camera.azimuth = 10.0, -90.0, 90.0
        self.option = mujoco.MjvOption()
        self.option.geomgroup[3] = 1  # the walls' contact skins: a wall's box is 0.2 mm thin from above
        self.option.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = 0
        self._mj, self._model, self._robot = mujoco, model, robot
        self._data = mujoco.MjData(model)  # the robot's pose copied: rendering leaves the physics' state alone

    def frame(self, trajectory: list[tuple[float, float]]) -> np.ndarray:
        """An ``(H, W, 3)`` uint8 frame of the scene now, with ``trajectory`` (cm) as a trail on the floor."""
        mujoco = self._mj
        self._data.qpos[:] = self._robot.data.qpos
        mujoco.mj_kinematics(self._model, self._data)
        self.renderer.update_scene(self._data, self.camera, self.option)
        scene = self.renderer.scene
        points = np.asarray(trajectory, dtype=np.float64).reshape(-1, 2) / 100.0
        for a, b in itertools.pairwise(points):
            if scene.ngeom >= scene.maxgeom or np.array_equal(a, b):
                continue
            geom = scene.geoms[scene.ngeom]
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.eye(3).ravel(), TRAIL)
            mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, 0.008, (*a, 0.003), (*b, 0.003))
            scene.ngeom += 1
        return np.asarray(self.renderer.render())

    def close(self) -> None:
        self.renderer.close()


def mujoco_robot(
    core: OfficeCore,
    generators: object,
    *,
    model: RealisticModel | None = None,
    artifacts: bool = True,
    heading_sd_rad: float = 0.01,
) -> MuJoCoRobot:
    """The robot of ``NomadOfficeMuJoCo-v0`` with its options (:class:`MuJoCoRobot`); it draws from no generator."""
    return MuJoCoRobot(core, model, artifacts=artifacts, heading_sd_rad=heading_sd_rad)


class NomadOfficeMuJoCoEnv(NomadOfficeEnv):
    """``NomadOfficeMuJoCo-v0``: the office task on the MuJoCo robot (:class:`MuJoCoRobot`).

    Spaces, evaluations and ``info`` are ``NomadOffice-v0``'s; the true pose is the physics'; a move that
    touches a wall is a collision (the core's rule: the robot stays where it was, the episode ends); the
    odometry in the observation is the robot's dead reckoning from its measured motion.

    ``render_mode="rgb_array"``: :meth:`render` draws the MuJoCo scene from above (:class:`TopDownView`);
    ``render_mode="lattice_rgb_array"``: the lattice picture of the other Nomad IDs (walls, regions, trail, sonar
    cones). Without an OpenGL context for MuJoCo, ``rgb_array`` draws the lattice picture and warns once.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}
    robot: MuJoCoRobot

    robot_factory = mujoco_robot

    def __init__(self, map: str | Path | None = None, **options: Any) -> None:
        super().__init__(map, **options)
        self._view: TopDownView | None = None
        self._no_view = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray | int, dict[str, Any]]:
        observation, info = super().reset(seed=seed, options=options)
        self.robot.reset_motion(self._pos)
        return observation, info

    def step(self, action: Any) -> tuple[np.ndarray | int, float, bool, bool, dict[str, Any]]:
        """The core's step on the physics' displacement; the odometry the robot's dead reckoning."""
        self.robot.place(self._pos)
        odometry = self._odo
        observation, reward, terminated, truncated, info = super().step(action)
        if not info["collision"]:
            self._odo = odometry + self.robot.odometry_cm
            if self.observe_odometry and isinstance(observation, np.ndarray):
                observation[sensors.N_READINGS :] = self.core.odometry(self._odo)
        return observation, reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The frame of :attr:`render_mode` (class docstring): the MuJoCo scene, or the lattice picture."""
        if self.render_mode == "rgb_array" and not self._no_view:
            if self._view is None:
                try:
                    self._view = TopDownView(self.robot)
                except Exception as err:  # the GL back ends fail with different errors (import, GL, MuJoCo)
                    self._no_view = True
                    reason = f"{type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}"
                    warnings.warn(
                        f"NomadOfficeMuJoCo-v0 cannot render the MuJoCo scene (no OpenGL context, "
                        f"MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}: {reason}); drawing the lattice picture "
                        f"instead; set MUJOCO_GL=egl or osmesa before mujoco is imported ({GL_PACKAGES})",
                        RuntimeWarning,
                        stacklevel=2,
                    )
            if self._view is not None:
                return self._view.frame(self._trajectory)
        if self.render_mode is None:
            return None
        return self.episodes.frame(self._pos, self._trajectory)

    def close(self) -> None:
        if self._view is not None:
            self._view.close()
            self._view = None
        super().close()
