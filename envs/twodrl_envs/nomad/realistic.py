"""A stand-in for the physical Nomad 200: sonar, infrared and odometry artifacts (``NomadOfficeReal-v0``).

The ideal simulator (``NomadOffice-v0``, :mod:`twodrl_envs.nomad.sensors`) reads the exact nearest wall in
each sonar cone and moves exactly 10 cm. A real Nomad 200 does neither; this module models the
documented reasons, each parameter with its source in ``docs/realistic.md``:

* **sonar** (Polaroid 6500 ranging module): a 30 degree beam, followed as a fan of rays through
  specular reflections. A ray that meets a wall at an incidence angle beyond the surface's critical
  angle is reflected away (no echo); it may meet another wall at a small enough angle and come back
  along the same path, giving a longer (multipath) range, or be lost, so the sonar reads its
  maximum. Echoes inside the transducer's ringing (blanking) time, closer than ``blank_cm``, are not
  heard. A reflected ray that comes back to the body may be heard by another transducer
  (cross-talk). Readings are reported in whole inches.
* **infrared** (Nomad Sensus 300, intensity-based): the reported distance is derived from the
  reflected intensity, which depends on the surface's reflectance and the angle of incidence, and
  saturates non-linearly at close range.
* **odometry**: the heading stays fixed (gyro), but each move's length and direction are off by a
  per-robot and per-episode systematic error plus per-move slip; the robot reports dead reckoning,
  so its odometry error grows over the episode.

Every artifact is a deterministic function of the pose and the walls, plus per-step noise drawn
counter-based from (episode key, step), so batched calls equal single calls and seeded runs repeat.
Wall surfaces are assigned per wall from a hash of its coordinates (the map files carry no
materials).
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.batched import BatchedNomadOffice
from twodrl_envs.nomad.core import OfficeCore, Robot
from twodrl_envs.nomad.geometry import MOVES_CM, ROBOT_RADIUS_CM, OfficeMap
from twodrl_envs.nomad.office import NomadOfficeEnv
from twodrl_envs.nomad.sensors import BEARINGS, IR_MAX_CM, N_SONAR, SONAR_MAX_CM, SONAR_MIN_CM, counter_hash

INCH_CM = 2.54
_MOTION_SALT = np.uint64(0xD1B54A32D192ED03)
_EPISODE_SALT = np.uint64(0x8CB92BA72F3D8DD7)
_SURFACE_SALT = np.uint64(0xA0761D6478BD642F)


@dataclass(frozen=True)
class Surface:
    """A wall material: diffuse infrared reflectance (1 = the IR calibration surface) and sonar critical angle."""

    name: str
    ir_reflectance: float
    critical_angle_deg: float
    share: float


DEFAULT_SURFACES = (
    Surface("painted plaster", 0.9, 7.5, 0.5),
    Surface("wood (doors, furniture)", 0.6, 10.0, 0.2),
    Surface("fabric partition", 0.25, 25.0, 0.2),
    Surface("glass or metal", 0.15, 3.0, 0.1),
)


def _positive(name: str, value: object, *, allow_zero: bool = False) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value):
        raise ValueError(f"RealisticModel.{name} must be a finite number, got {value!r}")
    if value < 0 or (value == 0 and not allow_zero):
        raise ValueError(f"RealisticModel.{name} must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")


@dataclass(frozen=True)
class RealisticModel:
    """Parameters of the stand-in robot's sensors and motion (sources in ``docs/realistic.md``)."""

    beam_half_angle_deg: float = 15.0
    rays_per_beam: int = 7
    max_reflections: int = 2
    blank_cm: float = 42.0
    crosstalk_prob: float = 0.3
    sonar_sd_cm: float = 1.0
    sonar_sd_frac: float = 0.01
    sonar_miss_prob: float = 0.02
    sonar_resolution_cm: float = INCH_CM
    ir_saturation_cm: float = 5.0
    ir_intensity_sd: float = 0.05
    scale_bias: float = -0.02
    scale_sd: float = 0.01
    misalignment_sd_rad: float = 0.01
    step_sd_cm: float = 0.5
    slip_sd_cm: float = 0.5
    surfaces: tuple[Surface, ...] = field(default=DEFAULT_SURFACES)
    surface_seed: int = 0

    def __post_init__(self) -> None:
        _positive("beam_half_angle_deg", self.beam_half_angle_deg)
        if not self.beam_half_angle_deg < 90:
            raise ValueError(f"RealisticModel.beam_half_angle_deg must be < 90, got {self.beam_half_angle_deg!r}")
        for name in ("rays_per_beam", "max_reflections", "surface_seed"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < (1 if name == "rays_per_beam" else 0):
                raise ValueError(f"RealisticModel.{name} must be an int >= 0 (rays_per_beam >= 1), got {value!r}")
        for name in ("blank_cm", "sonar_sd_cm", "sonar_sd_frac", "ir_intensity_sd", "scale_sd"):
            _positive(name, getattr(self, name), allow_zero=True)
        for name in ("misalignment_sd_rad", "step_sd_cm", "slip_sd_cm", "sonar_resolution_cm"):
            _positive(name, getattr(self, name), allow_zero=True)
        _positive("ir_saturation_cm", self.ir_saturation_cm)
        for name in ("crosstalk_prob", "sonar_miss_prob"):
            value = getattr(self, name)
            _positive(name, value, allow_zero=True)
            if value > 1:
                raise ValueError(f"RealisticModel.{name} must be in [0, 1], got {value!r}")
        bias = self.scale_bias
        if isinstance(bias, bool) or not isinstance(bias, int | float) or not -1 < bias < np.inf:
            raise ValueError(f"RealisticModel.scale_bias must be a number > -1, got {self.scale_bias!r}")
        if not self.surfaces or not all(isinstance(s, Surface) for s in self.surfaces):
            raise ValueError(f"RealisticModel.surfaces must be a non-empty tuple of Surface, got {self.surfaces!r}")
        for s in self.surfaces:
            if not (s.ir_reflectance > 0 and 0 <= s.critical_angle_deg < 90 and s.share >= 0):
                raise ValueError(f"RealisticModel.surfaces: bad surface {s!r}")
        if not sum(s.share for s in self.surfaces) > 0:
            raise ValueError("RealisticModel.surfaces: the shares must not all be 0")

    def describe(self) -> dict[str, Any]:
        """Parameters as JSON data (stored with a recorded database; tuples become lists)."""
        return json.loads(json.dumps(asdict(self)))

    # --- geometry -----------------------------------------------------------------------
    def scene(self, office: OfficeMap) -> Scene:
        """Per-map tables of this model: wall normals, materials, the ray fan."""
        return Scene(self, office)

    # --- motion -------------------------------------------------------------------------
    def displacement(self, actions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """True displacements ``(n, 2)`` cm of commanded 10 cm moves ``actions`` ``(n,)``.

        ``(1 + scale) * R(angle) * command + (along, lateral) slip``: ``scale`` is ``scale_bias``
        plus a per-episode draw (sd ``scale_sd``), ``angle`` a per-episode misalignment (sd
        ``misalignment_sd_rad``), both constant over an episode (systematic: dead-reckoning drift
        grows linearly with the moves); the slip is drawn per move (non-systematic).
        """
        command = MOVES_CM[np.asarray(actions, dtype=np.intp)]
        episode = _gaussians(counter_hash(keys ^ _EPISODE_SALT, np.zeros(len(keys), dtype=np.int64))[:, 0])
        move = _gaussians(counter_hash(keys ^ _MOTION_SALT, steps)[:, 0])
        scale = 1.0 + self.scale_bias + self.scale_sd * episode[:, 0]
        angle = self.misalignment_sd_rad * episode[:, 1]
        cos, sin = np.cos(angle), np.sin(angle)
        unit = command / np.linalg.norm(command, axis=1, keepdims=True)
        normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1)
        turned = np.stack([cos * command[:, 0] - sin * command[:, 1], sin * command[:, 0] + cos * command[:, 1]], 1)
        slip = self.step_sd_cm * move[:, :1] * unit + self.slip_sd_cm * move[:, 1:2] * normal
        return scale[:, None] * turned + slip


def _lanes(words: np.ndarray) -> np.ndarray:
    """The four 16-bit lanes ``(..., 4)`` of uint64 hash words, in the same order on every platform."""
    lanes = np.ascontiguousarray(words).view(np.uint16).reshape(*words.shape, 4)
    return lanes[..., ::-1] if sys.byteorder == "big" else lanes


def _gaussians(words: np.ndarray) -> np.ndarray:
    """Four standard-normal draws ``(n, 4)`` per hash word ``(n,)``."""
    return sensors.standard_normal(_lanes(words))


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _corners(walls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices shared by two walls ``(k, 2)`` and the unit vectors ``(k, 2, 2)`` along both walls from them."""
    ends = np.concatenate([walls[:, :2], walls[:, 2:]])
    others = np.concatenate([walls[:, 2:], walls[:, :2]])
    points, arms = [], []
    for i in range(len(ends)):
        same = np.flatnonzero(np.all(np.abs(ends - ends[i]) < 1e-6, axis=1))
        if len(same) == 2 and same[0] == i:
            vectors = others[same] - ends[i]
            points.append(ends[i])
            arms.append(vectors / np.linalg.norm(vectors, axis=1, keepdims=True))
    return np.array(points).reshape(-1, 2), np.array(arms).reshape(-1, 2, 2)


class Scene:
    """A :class:`RealisticModel` applied to one office: wall geometry and materials, the ray fan.

    ``surface`` ``(n_walls,)`` is the material index of each wall, a hash of the wall's
    coordinates (and ``surface_seed``), so a wall keeps its material when other walls change.
    """

    def __init__(self, model: RealisticModel, office: OfficeMap) -> None:
        self.model, self.office = model, office
        walls = office.walls
        self.a = walls[:, :2]
        self.e = walls[:, 2:] - walls[:, :2]
        self.normal = np.stack([-self.e[:, 1], self.e[:, 0]], axis=1) / np.linalg.norm(self.e, axis=1, keepdims=True)
        ids = np.round(walls * 10).astype(np.int64).astype(np.uint64)
        key = (ids * np.array([1, 3, 5, 7], dtype=np.uint64)[None] * np.uint64(0x9E3779B1)).sum(axis=1)
        word = counter_hash(key ^ _SURFACE_SALT ^ np.uint64(model.surface_seed), np.zeros(len(walls), np.int64))
        share = np.array([s.share for s in model.surfaces])
        cumulative = np.cumsum(share) / share.sum()
        self.surface = np.minimum(np.searchsorted(cumulative, word[:, 0] / 2.0**64, side="right"), len(share) - 1)
        self.cos_critical = np.cos(np.deg2rad([model.surfaces[k].critical_angle_deg for k in self.surface]))
        self.reflectance = np.array([model.surfaces[k].ir_reflectance for k in self.surface])
        half = np.deg2rad(model.beam_half_angle_deg)
        fan = np.linspace(-half, half, model.rays_per_beam) if model.rays_per_beam > 1 else np.zeros(1)
        angles = BEARINGS[:, None] + fan[None, :]  # (16, rays) clockwise from north
        self.ray_dirs = np.stack([np.sin(angles), np.cos(angles)], axis=-1)
        self.axes = np.stack([np.sin(BEARINGS), np.cos(BEARINGS)], axis=1)
        self.cos_half = np.cos(half)
        self.corners, self.corner_arms = _corners(walls)
        self._cross_ae = _cross(self.a, self.e)

    # --- tracing --------------------------------------------------------------------------
    def _nearest(self, origins: np.ndarray, dirs: np.ndarray, exclude: np.ndarray | None) -> tuple[np.ndarray, ...]:
        """Nearest wall hit ``(t, wall)`` of rays ``(..., 2)``; ``t = inf`` where none.

        Written as contiguous ``(rays, walls)`` products of per-ray and per-wall terms (the cross
        products expand into them), elementwise so that any batch size gives the same bits.
        """
        shape = np.broadcast_shapes(origins.shape, dirs.shape)[:-1]
        o = np.broadcast_to(origins, (*shape, 2)).reshape(-1, 2)
        d = np.broadcast_to(dirs, (*shape, 2)).reshape(-1, 2)
        ox, oy, dx, dy = o[:, :1], o[:, 1:], d[:, :1], d[:, 1:]
        ex, ey, ax, ay = self.e[:, 0], self.e[:, 1], self.a[:, 0], self.a[:, 1]
        denom = dx * ey - dy * ex  # cross(d, e)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (self._cross_ae - (ox * ey - oy * ex)) / denom  # cross(a - o, e) / cross(d, e)
            s = (ax * dy - ay * dx - (ox * dy - oy * dx)) / denom  # cross(a - o, d) / cross(d, e)
        hit = (denom != 0) & (t > 1e-9) & (s >= 0) & (s <= 1)
        if exclude is not None:
            hit &= np.arange(len(self.a)) != exclude.reshape(-1, 1)
        t = np.where(hit, t, np.inf)
        wall = np.argmin(t, axis=-1)
        return t[np.arange(len(t)), wall].reshape(shape), wall.reshape(shape)

    def echoes(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deterministic sonar echoes at robot centres ``(n, 2)``: ``(own, crosstalk)``, each ``(n, 16)`` cm.

        ``own[:, s]`` is the first echo sensor ``s`` hears of its own ping (diffuse returns at an
        incidence within the critical angle, directly or after up to ``max_reflections`` specular
        bounces, and specular paths back to its own transducer), ``crosstalk[:, j]`` the first echo
        of another transducer's ping that a specular path brings to transducer ``j``; echoes closer
        than ``blank_cm`` are unheard, ``inf`` means none.
        """
        model = self.model
        n = len(positions)
        shape = (n, N_SONAR, model.rays_per_beam)
        centre = np.broadcast_to(positions[:, None, None, :], (*shape, 2))
        origin = centre + ROBOT_RADIUS_CM * self.axes[None, :, None, :]
        direction = np.broadcast_to(self.ray_dirs[None], (*shape, 2)).copy()
        path = np.zeros(shape)
        alive = np.ones(shape, dtype=bool)
        exclude: np.ndarray | None = None
        own = np.full(shape, np.inf)
        cross_range = np.full(shape, np.inf)
        cross_to = np.zeros(shape, dtype=np.intp)
        source = np.broadcast_to(np.arange(N_SONAR)[None, :, None], shape)
        for bounce in range(model.max_reflections + 1):
            t, wall = self._nearest(origin, direction, exclude)
            if bounce > 0:  # a reflected ray may come back to the body
                rel = origin - centre
                b = np.einsum("...k,...k->...", direction, rel)
                disc = b * b - (np.einsum("...k,...k->...", rel, rel) - ROBOT_RADIUS_CM**2)
                with np.errstate(invalid="ignore"):
                    t_body = np.where(disc > 0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
                t_body = np.where(t_body > 1e-9, t_body, np.inf)
                back = alive & (t_body < t)
                hit_point = origin + np.where(back, t_body, 0.0)[..., None] * direction
                rel_hit = hit_point - centre
                receiver = np.round(-np.arctan2(rel_hit[..., 0], rel_hit[..., 1]) / np.deg2rad(22.5)).astype(np.intp)
                receiver %= N_SONAR
                arrival = -np.einsum("...k,...k->...", direction, self.axes[receiver])
                heard = back & (arrival >= self.cos_half)
                echo = (path + t_body) / 2
                mine = heard & (receiver == source)
                own = np.where(mine, np.minimum(own, echo), own)
                other = heard & ~mine
                cross_range = np.where(other, echo, cross_range)
                cross_to = np.where(other, receiver, cross_to)
                alive &= ~back
            alive &= np.isfinite(t)
            normal = self.normal[wall]
            cos_inc = np.abs(np.einsum("...k,...k->...", direction, normal))
            diffuse = alive & (cos_inc >= self.cos_critical[wall])
            own = np.where(diffuse, np.minimum(own, path + t), own)
            alive &= ~diffuse
            if not alive.any():
                break
            origin = origin + np.where(alive, t, 0.0)[..., None] * direction
            direction = direction - 2 * np.einsum("...k,...k->...", direction, normal)[..., None] * normal
            path = path + np.where(alive, t, 0.0)
            alive &= path < SONAR_MAX_CM
            exclude = wall
        limit = model.blank_cm
        own = np.minimum(own.min(axis=-1), self._corner_echoes(positions))
        own = np.where((own >= limit) & (own <= SONAR_MAX_CM), own, np.inf)
        cross_range = np.where((cross_range >= limit) & (cross_range <= SONAR_MAX_CM), cross_range, np.inf)
        crosstalk = np.full((n, N_SONAR), np.inf)
        rows = np.broadcast_to(np.arange(n)[:, None, None], shape)
        np.minimum.at(crosstalk, (rows.ravel(), cross_to.ravel()), cross_range.ravel())
        return own, crosstalk

    def _corner_echoes(self, positions: np.ndarray) -> np.ndarray:
        """Range ``(n, 16)`` to the nearest visible concave corner inside each sonar beam (a retroreflector)."""
        n = len(positions)
        if len(self.corners) == 0:
            return np.full((n, N_SONAR), np.inf)
        origin = positions[:, None, :] + ROBOT_RADIUS_CM * self.axes[None]  # (n, 16, 2)
        vec = self.corners[None, None] - origin[:, :, None, :]  # (n, 16, k, 2)
        dist = np.linalg.norm(vec, axis=-1)
        unit = vec / np.maximum(dist, 1e-9)[..., None]
        in_beam = np.einsum("nskc,sc->nsk", unit, self.axes) >= self.cos_half
        u1, u2 = self.corner_arms[:, 0], self.corner_arms[:, 1]
        back = -vec  # from the corner to the sensor
        turn = _cross(u1, u2)
        concave = (_cross(u1, back) * turn >= 0) & (_cross(back, u2) * turn >= 0) & (np.abs(turn) > 1e-9)
        t, _ = self._nearest(origin[:, :, None, :], unit, None)
        visible = t >= dist - 1e-6
        return np.where(in_beam & concave & visible, dist, np.inf).min(axis=-1)

    def infrared(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Axis range ``(n, 16)`` cm from the body surface and relative intensity ``rho cos(theta)`` of each IR beam."""
        origin = positions[:, None, :] + ROBOT_RADIUS_CM * self.axes[None]
        direction = np.broadcast_to(self.axes[None], origin.shape)
        t, wall = self._nearest(origin, direction, None)
        cos_inc = np.abs(np.einsum("...k,...k->...", direction, self.normal[wall]))
        return t, self.reflectance[wall] * cos_inc

    # --- readings -------------------------------------------------------------------------
    def deterministic(self, positions: np.ndarray) -> tuple[np.ndarray, ...]:
        """Everything about the readings at ``positions`` ``(n, 2)`` that does not change from ping to ping."""
        own, crosstalk = self.echoes(positions)
        ir_range, ir_gain = self.infrared(positions)
        return own, crosstalk, ir_range, ir_gain

    def ranges(
        self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray, cached: tuple[np.ndarray, ...] | None = None
    ) -> np.ndarray:
        """Readings ``(n, 32)`` in cm as the robot reports them (saturated): 16 sonar, then 16 IR.

        ``keys``/``steps`` ``(n,)`` draw the per-ping noise counter-based; ``cached`` may pass
        :meth:`deterministic` of the same positions.
        """
        model = self.model
        own, crosstalk, ir_range, ir_gain = self.deterministic(positions) if cached is None else cached
        lanes = _lanes(counter_hash(keys, steps))  # (n, 16, 4): miss, listen, IR noise, sonar noise
        listen = lanes[..., 1] < round(model.crosstalk_prob * 65536)
        sonar = np.minimum(own, np.where(listen, crosstalk, np.inf))
        heard = np.isfinite(sonar) & (lanes[..., 0] >= round(model.sonar_miss_prob * 65536))
        sonar = np.where(heard, sonar, 0.0)
        sonar += (model.sonar_sd_cm + model.sonar_sd_frac * sonar) * sensors.standard_normal(lanes[..., 3])
        if model.sonar_resolution_cm > 0:
            sonar = np.round(sonar / model.sonar_resolution_cm) * model.sonar_resolution_cm
        sonar = np.where(heard, np.clip(sonar, SONAR_MIN_CM, SONAR_MAX_CM), SONAR_MAX_CM)  # no echo: maximum
        # IR: intensity rho cos(theta) / d^2 (calibrated: rho = 1 head-on reads d), saturating as tanh
        with np.errstate(divide="ignore"):
            intensity = ir_gain / np.maximum(ir_range, 1e-6) ** 2
        ceiling = 1.0 / model.ir_saturation_cm**2
        measured = ceiling * np.tanh(intensity / ceiling)
        measured = measured * np.maximum(1.0 + model.ir_intensity_sd * sensors.standard_normal(lanes[..., 2]), 1e-3)
        with np.errstate(divide="ignore"):
            ir = np.where(measured > 0, 1.0 / np.sqrt(measured), np.inf)
        ir = np.clip(ir, 0.0, IR_MAX_CM)
        return np.concatenate([sonar, ir], axis=1)

    def readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Normalised readings ``(n, 32)`` float32 (the observation's sensor part)."""
        return sensors.normalise(self.ranges(positions, keys, steps))


class RealisticRobot(Robot):
    """The stand-in robot of a :class:`RealisticModel`: always off the lattice; readings of :meth:`Scene.readings`
    at the true pose; moves of :meth:`RealisticModel.displacement` (counter-based, no generator)."""

    on_lattice = False

    def __init__(self, core: OfficeCore, model: RealisticModel | None) -> None:
        if model is not None and not isinstance(model, RealisticModel):
            raise TypeError(f"model must be a RealisticModel or None, got {type(model).__name__}: {model!r}")
        super().__init__(core)
        self.model = RealisticModel() if model is None else model
        self.scene = self.model.scene(core.office)

    def pose_readings(self, positions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        return self.scene.readings(positions, keys, steps)

    def displacement(self, actions: np.ndarray, keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
        return self.model.displacement(actions, keys, steps)


def realistic_robot(core: OfficeCore, generators: object, *, model: RealisticModel | None = None) -> RealisticRobot:
    """The stand-in robot of ``NomadOfficeReal-v0`` with its option ``model`` (None: :class:`RealisticModel`'s
    defaults); counter-based, it draws from no generator."""
    return RealisticRobot(core, model)


class NomadOfficeRealEnv(NomadOfficeEnv):
    """``NomadOfficeReal-v0``: the office task on the stand-in robot of :class:`RealisticModel`.

    Readings are those of :meth:`Scene.ranges` at the true pose; moves follow
    :meth:`RealisticModel.displacement` and collide by the swept-disc test at the true pose; the
    odometry in the observation is dead reckoning (start plus the commanded moves that did not
    collide). Evaluations, ``info`` keys and the observation layout are those of ``NomadOffice-v0``.
    The robot is a :class:`RealisticRobot` (``env.robot``).
    """

    robot_factory = realistic_robot


class BatchedNomadOfficeReal(BatchedNomadOffice):
    """``num_envs`` stand-in robots: ``info["position_cm"]`` is the true pose, the odometry is dead reckoning.

    All per-step randomness is counter-based, so sub-env ``i`` reset with seed ``s`` equals
    ``gym.make("twodrl_envs:NomadOfficeReal-v0")`` reset with seed ``s`` and reset again after every episode.
    """

    single_env = NomadOfficeRealEnv
