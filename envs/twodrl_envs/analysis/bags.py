"""A MEMORABLE database from a robot's ROS 2 bag (``sb3-twodrl-record-database --from-bag``, extra ``sb3-twodrl[ros]``).

A Nomad-like robot publishes its 16 sonar and 16 infrared ranges as ``sensor_msgs/msg/Range`` topics (one per
sensor, e.g. ``/sonar_0`` .. ``/sonar_15``) or as one ``sensor_msgs/msg/LaserScan`` per ring (16 ranges, sensor
``i`` at ``i * 22.5`` degrees counter-clockwise from the robot's front), and its odometry as
``nav_msgs/msg/Odometry`` (the conventions below; the reference: ``docs/bags.md``). :func:`read_bag` turns the
bag into the arrays the CSV import produces (the positions the readings were taken at and the 32 ranges in cm)
and :func:`import_bag` files them under lattice cells by the same code
(:func:`~twodrl_envs.memorable.database.import_readings`).

* **a reading**: the 32 ranges once every sensor has published since the previous reading, at the latest pose;
  readings before the first pose are skipped (counted in the metadata);
* **what each message says about itself** is checked (:func:`message_ranges`): its frame id against the sensor
  layout (:func:`sensor_rings`), a ``Range``'s ``radiation_type``, the declared ``min_range``/``max_range``
  against the sensor model (a bag in centimetres declares a sonar's 600), every range (none beyond
  ``max_range``), and a scan's layout: a clockwise scan or one starting behind the robot is reordered to the
  sensors' numbering (:func:`scan_columns`);
* **units**: metres in the messages (REP 103), cm in the database; ``+inf`` (no echo within ``max_range``) reads
  the sensor's maximum and ``-inf`` (too close) its minimum (REP 117), and every range is saturated to the
  sensors' ranges (:mod:`twodrl_envs.nomad.sensors`), as the robot reports them;
* **the pose**: the odometry's (or a ``geometry_msgs/msg/PoseStamped`` / ``PoseWithCovarianceStamped`` topic's)
  position. ``pose_frame="start"``: the odometry frame of a robot switched on at the map's start facing north
  (REP 103: x forward = north, y left = west); ``"map"``: the map's own frame (x east, y north), as a localiser
  publishes it.

Every problem (no such bag, a missing topic, a wrong message type, no odometry, a message that contradicts the
layout, no complete reading) is a one-line ``ValueError`` naming the topic, and the command flag that fixes it
where one does. :func:`write_bag` writes a drive as such a robot would log it (the tests'
round trip). ``rosbags`` (pure Python, no ROS installation) is imported when a bag is read or written.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from twodrl_envs.memorable.database import SensorDatabase, import_readings
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.sensors import HIGH_CM, LOW_CM, N_IR, N_SONAR

RANGE = "sensor_msgs/msg/Range"
SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"
POSE_TYPES = (ODOMETRY, "geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/PoseWithCovarianceStamped")
POSE_FRAMES = ("start", "map")
STORAGES = ("sqlite3", "mcap")
ROS_HINT = 'reading or writing ROS 2 bags needs rosbags: pip install "sb3-twodrl[ros]"'

# The conventions of a bag this project writes and reads (write_bag, the survey drive): import these, do not spell
# them again. Ranges are metres (REP 103), +inf = no echo within max_range, -inf = too close (REP 117).
SONAR_TOPIC = "/sonar_{i}"  # one sensor_msgs/msg/Range topic per sonar, i = 0..15
IR_TOPIC = "/ir_{i}"  # one Range topic per infrared sensor
SONAR_SCAN_TOPIC = "/sonar_scan"  # or one sensor_msgs/msg/LaserScan per ring
IR_SCAN_TOPIC = "/ir_scan"
ODOMETRY_TOPIC = "/odom"  # nav_msgs/msg/Odometry: the robot's own odometry (drift included)
GROUND_TRUTH_TOPIC = "/ground_truth"  # nav_msgs/msg/Odometry: a simulator's true pose, frame MAP_FRAME
SONAR_FRAME = "sonar_{i}"  # header.frame_id of sonar i's Range
IR_FRAME = "ir_{i}"
SONAR_RING_FRAME = "sonar_ring"  # header.frame_id of a ring's LaserScan (x forward, at the robot's centre)
IR_RING_FRAME = "ir_ring"
ODOMETRY_FRAME = "odom"  # header.frame_id of the odometry (pose_frame "start")
MAP_FRAME = "map"  # header.frame_id of a pose in the map's frame (pose_frame "map")
BASE_FRAME = "base_link"  # child_frame_id of the odometry
ULTRASOUND, INFRARED = 0, 1  # sensor_msgs/msg/Range.radiation_type of a sonar / an infrared sensor
SONAR_FIELD_OF_VIEW_RAD = float(np.deg2rad(22.5))  # Range.field_of_view: the sonar's cone; infrared: a beam, 0
IR_FIELD_OF_VIEW_RAD = 0.0
SCAN_ANGLE_MIN_RAD = 0.0  # a ring's LaserScan: sensor 0 at the front, counter-clockwise (REP 103)
SCAN_INCREMENT_RAD = float(np.deg2rad(22.5))
SONAR_RANGE_M = (float(LOW_CM[0]) / 100.0, float(HIGH_CM[0]) / 100.0)  # (min_range, max_range), metres
IR_RANGE_M = (float(LOW_CM[N_SONAR]) / 100.0, float(HIGH_CM[N_SONAR]) / 100.0)


LIMIT_TOLERANCE = 0.1  # declared min_range/max_range may differ from the sensor model's by this share of its maximum
ANGLE_TOLERANCE_RAD = 1e-3  # a LaserScan's angle_min and angle_increment against the 22.5 degree layout
RADIATION = {ULTRASOUND: "ULTRASOUND", INFRARED: "INFRARED"}


def import_rosbags() -> Any:
    """The ``rosbags`` package, or ``ModuleNotFoundError`` saying which extra installs it."""
    try:
        import rosbags.highlevel
        import rosbags.rosbag2
        import rosbags.typesys
    except ImportError as err:
        raise ModuleNotFoundError(f"{ROS_HINT} ({err})", name="rosbags") from err
    return rosbags


def ring_topics(pattern: str, what: str) -> list[str]:
    """The topics of a ring of 16 sensors: ``pattern`` with ``{i}`` (16 ``Range`` topics), else one ``LaserScan``."""
    if not isinstance(pattern, str) or not pattern.startswith("/"):
        raise ValueError(f"{what} topic must be a topic name starting with '/', got {pattern!r} (--{what}-topic)")
    if "{i}" in pattern:
        return [pattern.replace("{i}", str(i)) for i in range(N_SONAR)]
    return [pattern]


@dataclass(frozen=True)
class Ring:
    """What a bag must say about one ring of 16 sensors: its topics, their frame ids, type and ranges."""

    what: str  # "sonar" or "ir"
    first: int  # the ring's first column of the 32 readings
    topics: list[str]
    frames: list[str]  # the expected header.frame_id of each topic
    msgtype: str  # RANGE (a topic per sensor) or SCAN (one topic)
    radiation: int  # Range.radiation_type
    range_m: tuple[float, float]  # the sensor model's (min, max), metres

    @property
    def flags(self) -> str:
        """The command flag and Python argument that name this ring's topics."""
        return f"--{self.what}-topic / {self.what}="

    @property
    def frame_flags(self) -> str:
        return f"--{self.what}-frame / {self.what}_frame="


def sensor_rings(
    sonar: str = SONAR_TOPIC, ir: str = IR_TOPIC, sonar_frame: str | None = None, ir_frame: str | None = None
) -> tuple[Ring, Ring]:
    """The two rings of a bag's topic patterns and frame-id patterns (``None``: this project's frame ids,
    :data:`SONAR_FRAME` for ``Range`` topics, :data:`SONAR_RING_FRAME` for a ``LaserScan``)."""
    rings = []
    for what, pattern, frame, first in (("sonar", sonar, sonar_frame, 0), ("ir", ir, ir_frame, N_SONAR)):
        topics = ring_topics(pattern, what)
        per_sensor = len(topics) > 1
        if frame is None:
            frame = {("sonar", True): SONAR_FRAME, ("sonar", False): SONAR_RING_FRAME}.get(
                (what, per_sensor), IR_FRAME if per_sensor else IR_RING_FRAME
            )
        if not isinstance(frame, str) or not frame:
            raise ValueError(
                f"{what}_frame must be a frame id (a pattern with {{i}} for Range topics), got {frame!r} "
                f"(--{what}-frame)"
            )
        frames = [frame.replace("{i}", str(i)) for i in range(len(topics))]
        sonar_ring = what == "sonar"
        rings.append(
            Ring(
                what,
                first,
                topics,
                frames,
                RANGE if per_sensor else SCAN,
                ULTRASOUND if sonar_ring else INFRARED,
                SONAR_RANGE_M if sonar_ring else IR_RANGE_M,
            )
        )
    return rings[0], rings[1]


def _check_frame(pose_frame: object) -> str:
    if pose_frame not in POSE_FRAMES:
        raise ValueError(f"pose_frame must be one of {POSE_FRAMES}, got {pose_frame!r}")
    return str(pose_frame)


def _to_map(xy_m: np.ndarray, pose_frame: str, start: tuple[float, float]) -> np.ndarray:
    """Positions (m) of the pose topic's frame as cm in the map's frame."""
    xy_cm = np.asarray(xy_m, dtype=np.float64) * 100.0
    if pose_frame == "map":
        return xy_cm
    return np.stack([start[0] - xy_cm[..., 1], start[1] + xy_cm[..., 0]], axis=-1)  # x forward = north, y = west


def _from_map(xy_cm: np.ndarray, pose_frame: str, start: tuple[float, float]) -> np.ndarray:
    """:func:`_to_map`'s inverse: map positions (cm) as metres in the pose topic's frame."""
    xy_cm = np.asarray(xy_cm, dtype=np.float64)
    if pose_frame == "map":
        return xy_cm / 100.0
    return np.stack([xy_cm[..., 1] - start[1], start[0] - xy_cm[..., 0]], axis=-1) / 100.0


def _saturate(values_m: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Ranges (metres, ``(n, 32)``) as the database's cm: +-inf and beyond the sensor model's limits saturated."""
    cm = np.asarray(values_m, dtype=np.float64) * 100.0
    cm = np.where(np.isposinf(cm), high, np.where(np.isneginf(cm), low, cm))
    return np.clip(cm, low, high)


CENTIMETRES = "ranges in centimetres? ROS ranges are metres (REP 103): record the bag in metres"


def _check_limits(where: str, ring: Ring, low: float, high: float) -> None:
    """The declared ``min_range``/``max_range`` (metres) against the sensor model's, within :data:`LIMIT_TOLERANCE`."""
    model_low, model_high = ring.range_m
    tolerance = LIMIT_TOLERANCE * model_high
    if abs(low - model_low) <= tolerance and abs(high - model_high) <= tolerance:  # NaN or inf fail too
        return
    declared = f"{where} declares min_range {low:g}, max_range {high:g}"
    if abs(high / 100 - model_high) <= tolerance:
        raise ValueError(
            f"{declared}: {CENTIMETRES} (the sensor model's {ring.what} reads {model_low:g}-{model_high:g} m)"
        )
    raise ValueError(
        f"{declared}; the sensor model's {ring.what} reads {model_low:g}-{model_high:g} m (within {tolerance:g} m): "
        f"is it the {ring.what} ring? ({ring.flags})"
    )


def scan_columns(where: str, angle_min: float, increment: float, count: int) -> np.ndarray:
    """Which of the ring's 16 sensors (0 at the front, counter-clockwise) each of a ``LaserScan``'s ranges is:
    any ``angle_min`` on the 22.5 degree layout, counter-clockwise (positive ``angle_increment``) or clockwise."""
    step = SCAN_INCREMENT_RAD
    if count != N_SONAR:
        raise ValueError(f"{where} has {count} ranges, expected {N_SONAR} (one per sensor)")
    if not abs(abs(increment) - step) <= ANGLE_TOLERANCE_RAD:
        raise ValueError(
            f"{where} has angle_increment {increment:g} rad, expected +-{step:.6f} (22.5 degrees, one per sensor)"
        )
    first = angle_min / step
    if not abs(first - round(first)) * step <= ANGLE_TOLERANCE_RAD:
        raise ValueError(
            f"{where} has angle_min {angle_min:g} rad, not a multiple of 22.5 degrees: its ranges are not the sensors'"
        )
    return (round(first) + int(np.sign(increment)) * np.arange(N_SONAR)) % N_SONAR


def message_ranges(
    where: str, ring: Ring, index: int, msgtype: str, msg: Any
) -> tuple[int, float] | tuple[np.ndarray, np.ndarray]:
    """The column(s) (of the 32) and range(s) (metres, as sent) of one ring message, once what it says about itself
    is checked: frame id, radiation type, declared ranges, scan layout, each range (NaN, negative, beyond max_range).
    A ``Range`` is read as a float (a bag holds hundreds of thousands)."""
    frame = msg.header.frame_id
    if frame != ring.frames[index]:
        raise ValueError(
            f"{where} has frame_id {frame!r}, expected {ring.frames[index]!r} (the sensor layout; a robot whose frames "
            f"are named otherwise: {ring.frame_flags}PATTERN, with {{i}} for Range topics)"
        )
    if msgtype == RANGE:
        if msg.radiation_type != ring.radiation:
            name = RADIATION.get(msg.radiation_type, "unknown")
            raise ValueError(
                f"{where} has radiation_type {msg.radiation_type} ({name}), expected {ring.radiation} "
                f"({RADIATION[ring.radiation]}) for the {ring.what} ring ({ring.flags})"
            )
        low, high = float(msg.min_range), float(msg.max_range)
        _check_limits(where, ring, low, high)
        value = float(msg.range)
        if not (math.isinf(value) or 0 <= value <= high * (1 + 1e-6)):  # NaN too
            _check_values(where, ring, np.array([value]), high)
        return ring.first + index, value
    low, high = float(msg.range_min), float(msg.range_max)
    values = np.asarray(msg.ranges, dtype=np.float64)
    columns = scan_columns(where, float(msg.angle_min), float(msg.angle_increment), len(values))
    _check_limits(where, ring, low, high)
    _check_values(where, ring, values, high)
    return ring.first + columns, values


def _check_values(where: str, ring: Ring, values: np.ndarray, high: float) -> None:
    """Each range (metres) a number from 0 to ``high`` (the declared max_range), or +-inf (REP 117)."""
    if np.isnan(values).any():
        raise ValueError(f"{where} has a NaN range")
    finite = values[np.isfinite(values)]
    if (finite < 0).any():
        raise ValueError(f"{where} reads {finite.min():g} m, a negative range (too close is -inf, REP 117)")
    if (finite > high * (1 + 1e-6)).any():
        worst = f"{where} reads {finite.max():g} m, beyond its max_range {high:g} m"
        if finite.max() > 10 * ring.range_m[1]:
            raise ValueError(f"{worst}: {CENTIMETRES}")
        raise ValueError(f"{worst} (no echo within max_range is +inf, REP 117)")


def _position(msg: Any) -> np.ndarray:
    """x, y (m) of an ``Odometry``, ``PoseWithCovarianceStamped`` or ``PoseStamped``."""
    pose = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
    return np.array([pose.position.x, pose.position.y])


def read_bag(path: str | Path, **options: Any) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Positions ``(n, 2)`` cm in ``map``'s frame, readings ``(n, 32)`` cm and statistics of a bag's readings: those
    of :func:`read_bag_readings` (``options`` are its keyword arguments)."""
    read = read_bag_readings(path, **options)
    return read.positions, read.readings, read.stats


@dataclass(frozen=True)
class BagReadings:
    """A bag's readings (:func:`read_bag_readings`), with where and when each was taken."""

    positions: np.ndarray
    """``(n, 2)`` cm in the map's frame."""
    readings: np.ndarray
    """``(n, 32)`` cm, saturated to the sensors' ranges."""
    stats: dict[str, Any]
    stamps: list[int]
    """Each reading's bag time (ns): that of the message that completed it."""
    poses: list[tuple[str, float, float]]
    """Each reading's pose as its topic says it: ``(frame_id, x, y)``, metres."""


def read_bag_readings(
    path: str | Path,
    *,
    map: str | Path | None = None,
    sonar: str = SONAR_TOPIC,
    ir: str = IR_TOPIC,
    odometry: str = ODOMETRY_TOPIC,
    pose: str | None = None,
    pose_frame: str = "start",
    sonar_frame: str | None = None,
    ir_frame: str | None = None,
) -> BagReadings:
    """The readings of a bag: positions ``(n, 2)`` cm in ``map``'s frame, readings ``(n, 32)`` cm, statistics, and
    each reading's bag time and pose message (:class:`BagReadings`).

    ``sonar`` / ``ir``: a topic pattern with ``{i}`` (16 ``Range`` topics) or one ``LaserScan`` topic;
    ``sonar_frame`` / ``ir_frame``: their frame ids (:func:`sensor_rings`); ``odometry``: the ``Odometry`` topic,
    the pose source unless ``pose`` names another topic (then ``odometry`` is not read). Each message is checked
    (:func:`message_ranges`).
    """
    frame = _check_frame(pose_frame)
    rings = sensor_rings(sonar, ir, sonar_frame, ir_frame)  # checked before the bag is opened
    for what, topic, flag in (("odometry", odometry, "--odom-topic"), ("pose", pose, "--pose-topic")):
        if (topic is not None or what == "odometry") and (not isinstance(topic, str) or not topic.startswith("/")):
            raise ValueError(f"{what} topic must be a topic name starting with '/', got {topic!r} ({flag})")
    pose_topic = odometry if pose is None else pose
    pose_flags = (
        "--odom-topic / odometry=, or a pose topic: --pose-topic / pose=" if pose is None else "--pose-topic / pose="
    )
    rosbags = import_rosbags()
    path = Path(path)
    name = str(path)
    if not path.exists():
        raise ValueError(f"bag {name} does not exist")
    start = office_core(map).office.start
    typestore = rosbags.typesys.get_typestore(rosbags.typesys.Stores.ROS2_HUMBLE)
    try:
        reader = rosbags.highlevel.AnyReader([path], default_typestore=typestore)
        reader.open()
    except Exception as err:  # rosbags raises its own errors for a file that is no bag
        raise ValueError(f"bag {name} cannot be read: {type(err).__name__}: {err}") from err
    try:
        types = {c.topic: c.msgtype for c in reader.connections}
        topics = ", ".join(sorted(types)) or "none"
        if pose_topic not in types:
            what = "no odometry" if pose is None else "no pose"
            raise ValueError(f"bag {name}: {what}: no topic {pose_topic!r} (its topics: {topics}; {pose_flags})")
        expected_pose = (ODOMETRY,) if pose is None else POSE_TYPES
        if types[pose_topic] not in expected_pose:
            raise ValueError(
                f"bag {name}: topic {pose_topic!r} is {types[pose_topic]}, expected {' or '.join(expected_pose)} "
                f"({pose_flags})"
            )
        slots: dict[str, tuple[Ring, int]] = {}
        for ring in rings:
            for j, topic in enumerate(ring.topics):
                if topic not in types:
                    raise ValueError(f"bag {name}: no topic {topic!r} (its topics: {topics}; {ring.flags})")
                if types[topic] != ring.msgtype:
                    raise ValueError(
                        f"bag {name}: topic {topic!r} is {types[topic]}, expected {ring.msgtype} ({ring.flags})"
                    )
                slots[topic] = (ring, j)
        wanted = [c for c in reader.connections if c.topic in slots or c.topic == pose_topic]
        current = np.full(N_SONAR + N_IR, np.nan)
        fresh = np.zeros(N_SONAR + N_IR, dtype=bool)
        last_pose: np.ndarray | None = None
        last_frame = ""
        positions, readings, before_pose, poses = [], [], 0, 0
        stamps: list[int] = []
        taken: list[tuple[str, float, float]] = []
        for connection, stamp, raw in reader.messages(connections=wanted):
            msg = reader.deserialize(raw, connection.msgtype)
            topic = connection.topic
            if topic == pose_topic:
                last_pose, last_frame = _position(msg), msg.header.frame_id
                poses += 1
                if topic not in slots:
                    continue
            ring, j = slots[topic]
            columns, values = message_ranges(f"bag {name}: topic {topic!r}", ring, j, connection.msgtype, msg)
            current[columns] = values
            fresh[columns] = True
            if fresh.all():
                fresh[:] = False
                if last_pose is None:
                    before_pose += 1
                    continue
                positions.append(_to_map(last_pose, frame, start))
                readings.append(current.copy())
                stamps.append(stamp)
                taken.append((last_frame, float(last_pose[0]), float(last_pose[1])))
    finally:
        reader.close()
    if poses == 0:
        raise ValueError(
            f"bag {name}: {'no odometry' if pose is None else 'no pose'}: topic {pose_topic!r} has no messages"
        )
    if not readings:
        raise ValueError(
            f"bag {name}: no complete reading (every one of the 32 sensors after a pose on {pose_topic!r})"
        )
    stats = {"readings": len(readings), "readings_before_first_pose": before_pose, "poses": poses}
    return BagReadings(np.array(positions), _saturate(np.array(readings), LOW_CM, HIGH_CM), stats, stamps, taken)


def import_bag(
    path: str | Path,
    *,
    map: str | Path | None = None,
    sonar: str = SONAR_TOPIC,
    ir: str = IR_TOPIC,
    odometry: str = ODOMETRY_TOPIC,
    pose: str | None = None,
    pose_frame: str = "start",
    sonar_frame: str | None = None,
    ir_frame: str | None = None,
    per_cell: int | None = None,
    require_all_cells: bool = True,
    tolerance_cm: float = 5.0,
) -> SensorDatabase:
    """A database of ``map`` from a bag's readings (:func:`read_bag`), filed under lattice cells as the CSV import
    files them (:func:`~twodrl_envs.memorable.database.import_readings`: ``per_cell``, ``require_all_cells``,
    ``tolerance_cm``)."""
    positions, readings, stats = read_bag(
        path,
        map=map,
        sonar=sonar,
        ir=ir,
        odometry=odometry,
        pose=pose,
        pose_frame=pose_frame,
        sonar_frame=sonar_frame,
        ir_frame=ir_frame,
    )
    recording = {
        "source": "ros2 bag",
        "file": Path(path).name,
        "topics": {"sonar": sonar, "ir": ir, "pose": pose or odometry},
        "pose_frame": pose_frame,
        **stats,
        "how": "imported from a ROS 2 bag: a reading once all 32 sensors have published, at the latest pose, "
        "snapped to the 10 cm lattice",
    }
    return import_readings(
        positions,
        readings,
        map=map,
        source=f"bag {path}",
        recording=recording,
        require_all_cells=require_all_cells,
        tolerance_cm=tolerance_cm,
        per_cell=per_cell,
    )


def header(typestore: Any, ns: int, frame_id: str) -> Any:
    """A ``std_msgs/msg/Header`` at ``ns`` nanoseconds."""
    types = typestore.types
    stamp = types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
    return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)


def range_message(typestore: Any, ns: int, value_cm: float, column: int) -> Any:
    """Sensor ``column``'s (of the 32) ``Range`` as this project writes it: metres, its frame id, radiation type
    and ranges; at the sensor's maximum, ``+inf`` (REP 117)."""
    infrared = column >= N_SONAR
    low, high = IR_RANGE_M if infrared else SONAR_RANGE_M
    i = column % N_SONAR
    return typestore.types[RANGE](
        header=header(typestore, ns, (IR_FRAME if infrared else SONAR_FRAME).replace("{i}", str(i))),
        radiation_type=INFRARED if infrared else ULTRASOUND,
        field_of_view=IR_FIELD_OF_VIEW_RAD if infrared else SONAR_FIELD_OF_VIEW_RAD,
        min_range=low,
        max_range=high,
        range=np.inf if value_cm >= HIGH_CM[column] else float(value_cm / 100.0),
    )


def scan_message(typestore: Any, ns: int, values_cm: np.ndarray, first: int) -> Any:
    """A ring's 16 ranges (cm, sensor 0 first; ``first`` 0: sonar, 16: infrared) as this project's ``LaserScan``:
    counter-clockwise from the front, metres, the ring's frame id; at the sensors' maximum, ``+inf``."""
    infrared = first >= N_SONAR
    low, high = IR_RANGE_M if infrared else SONAR_RANGE_M
    values_cm = np.asarray(values_cm, dtype=np.float64)
    return typestore.types[SCAN](
        header=header(typestore, ns, IR_RING_FRAME if infrared else SONAR_RING_FRAME),
        angle_min=SCAN_ANGLE_MIN_RAD,
        angle_max=SCAN_ANGLE_MIN_RAD + SCAN_INCREMENT_RAD * (N_SONAR - 1),
        angle_increment=SCAN_INCREMENT_RAD,
        time_increment=0.0,
        scan_time=0.0,
        range_min=low,
        range_max=high,
        ranges=np.where(values_cm >= HIGH_CM[first], np.inf, values_cm / 100.0).astype(np.float32),
        intensities=np.zeros(0, dtype=np.float32),
    )


def odometry_message(typestore: Any, ns: int, xy_m: np.ndarray, frame_id: str = ODOMETRY_FRAME) -> Any:
    """An ``Odometry`` at ``xy_m`` (metres, in ``frame_id``), heading along x, at rest."""
    types = typestore.types
    point, quaternion, vector = (types[f"geometry_msgs/msg/{t}"] for t in ("Point", "Quaternion", "Vector3"))
    still = vector(x=0.0, y=0.0, z=0.0)
    return types[ODOMETRY](
        header=header(typestore, ns, frame_id),
        child_frame_id=BASE_FRAME,
        pose=types["geometry_msgs/msg/PoseWithCovariance"](
            pose=types["geometry_msgs/msg/Pose"](
                position=point(x=float(xy_m[0]), y=float(xy_m[1]), z=0.0),
                orientation=quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
            covariance=np.zeros(36),
        ),
        twist=types["geometry_msgs/msg/TwistWithCovariance"](
            twist=types["geometry_msgs/msg/Twist"](linear=still, angular=still), covariance=np.zeros(36)
        ),
    )


def write_bag(
    path: str | Path,
    positions_cm: np.ndarray,
    ranges_cm: np.ndarray,
    *,
    map: str | Path | None = None,
    sonar: str = SONAR_TOPIC,
    ir: str = IR_TOPIC,
    odometry: str = ODOMETRY_TOPIC,
    pose_frame: str = "start",
    period_s: float = 0.5,
    storage: str = "sqlite3",
    ground_truth_cm: np.ndarray | None = None,
) -> Path:
    """Write a drive (positions ``(n, 2)`` cm in ``map``'s frame, readings ``(n, 32)`` cm) as a ROS 2 bag (``storage``
    ``"sqlite3"`` or ``"mcap"``) as a Nomad-like robot logs it: per reading, its odometry (frame
    :data:`ODOMETRY_FRAME`, or :data:`MAP_FRAME` for ``pose_frame="map"``), then each sensor's ``Range``
    (:func:`range_message`) or each ring's ``LaserScan`` (:func:`scan_message`), ``period_s`` apart.
    ``ground_truth_cm`` ``(n, 2)``: the true positions, as ``Odometry`` on :data:`GROUND_TRUTH_TOPIC` in the map's
    frame."""
    frame = _check_frame(pose_frame)
    if storage not in STORAGES:
        raise ValueError(f"storage must be one of {STORAGES}, got {storage!r}")
    if isinstance(period_s, bool) or not isinstance(period_s, int | float) or not 0.001 <= period_s < 1e6:
        raise ValueError(f"period_s must be a number of seconds from 0.001, got {period_s!r}")
    positions_cm = np.asarray(positions_cm, dtype=np.float64)
    ranges_cm = np.asarray(ranges_cm, dtype=np.float64)
    if positions_cm.ndim != 2 or positions_cm.shape[1] != 2 or ranges_cm.shape != (len(positions_cm), 32):
        raise ValueError(
            f"positions_cm must be (n, 2) and ranges_cm (n, 32), got {positions_cm.shape} and {ranges_cm.shape}"
        )
    if ground_truth_cm is not None:
        ground_truth_cm = np.asarray(ground_truth_cm, dtype=np.float64)
        if ground_truth_cm.shape != positions_cm.shape:
            raise ValueError(
                f"ground_truth_cm must be {positions_cm.shape} as positions_cm, got {ground_truth_cm.shape}"
            )
    rings = sensor_rings(sonar, ir)
    rosbags = import_rosbags()
    typestore = rosbags.typesys.get_typestore(rosbags.typesys.Stores.ROS2_HUMBLE)
    start = office_core(map).office.start
    odometry_xy = _from_map(positions_cm, frame, start)
    odometry_frame = MAP_FRAME if frame == "map" else ODOMETRY_FRAME
    path = Path(path)
    plugin = rosbags.rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbags.rosbag2.StoragePlugin.SQLITE3
    with rosbags.rosbag2.Writer(path, version=8, storage_plugin=plugin) as writer:
        odom = writer.add_connection(odometry, ODOMETRY, typestore=typestore)
        truth = (
            None
            if ground_truth_cm is None
            else writer.add_connection(GROUND_TRUTH_TOPIC, ODOMETRY, typestore=typestore)
        )
        connections = [
            (ring, [writer.add_connection(t, ring.msgtype, typestore=typestore) for t in ring.topics]) for ring in rings
        ]
        for n, (xy, values) in enumerate(zip(odometry_xy, ranges_cm, strict=True)):
            ns = round(n * period_s * 1e9) + 10**9
            writer.write(
                odom, ns, typestore.serialize_cdr(odometry_message(typestore, ns, xy, odometry_frame), ODOMETRY)
            )
            if truth is not None and ground_truth_cm is not None:
                message = odometry_message(typestore, ns, ground_truth_cm[n] / 100.0, MAP_FRAME)
                writer.write(truth, ns, typestore.serialize_cdr(message, ODOMETRY))
            offset = 0
            for ring, ring_connections in connections:
                for j, connection in enumerate(ring_connections):
                    offset += 1000
                    if ring.msgtype == RANGE:
                        msg = range_message(typestore, ns + offset, float(values[ring.first + j]), ring.first + j)
                    else:
                        msg = scan_message(
                            typestore, ns + offset, values[ring.first : ring.first + N_SONAR], ring.first
                        )
                    writer.write(connection, ns + offset, typestore.serialize_cdr(msg, ring.msgtype))
    return path
