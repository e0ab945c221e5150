"""A MEMORABLE database from a robot's ROS 2 bag (``sb3-twodrl-record-database --from-bag``, extra ``sb3-twodrl[ros]``).

A Nomad-like robot publishes its 16 sonar and 16 infrared ranges as ``sensor_msgs/msg/Range`` topics (one per
sensor, e.g. ``/sonar_0`` .. ``/sonar_15``) or as one ``sensor_msgs/msg/LaserScan`` per ring (16 ranges, sensor
``i`` at ``i * 22.5`` degrees counter-clockwise from the robot's front), and its odometry as
``nav_msgs/msg/Odometry``. :func:`read_bag` turns the bag into the arrays the CSV import produces (the positions
the readings were taken at and the 32 ranges in cm) and :func:`import_bag` files them under lattice cells by the
same code (:func:`~twodrl_envs.memorable.database.import_readings`).

* **a reading**: the 32 ranges once every sensor has published since the previous reading, at the latest pose;
  readings before the first pose are skipped (counted in the metadata);
* **units**: metres in the messages (REP 103), cm in the database; ``+inf`` (no echo within ``max_range``) reads
  the sensor's maximum and ``-inf`` (too close) its minimum (REP 117), and every range is saturated to the
  sensors' ranges (:mod:`twodrl_envs.nomad.sensors`), as the robot reports them;
* **the pose**: the odometry's (or a ``geometry_msgs/msg/PoseStamped`` / ``PoseWithCovarianceStamped`` topic's)
  position. ``pose_frame="start"``: the odometry frame of a robot switched on at the map's start facing north
  (REP 103: x forward = north, y left = west); ``"map"``: the map's own frame (x east, y north), as a localiser
  publishes it.

Every problem (no such bag, a missing topic, a wrong message type, no odometry, no complete reading) is a
one-line ``ValueError`` naming it. :func:`write_bag` writes a drive as such a robot would log it (the tests'
round trip). ``rosbags`` (pure Python, no ROS installation) is imported when a bag is read or written.
"""

from __future__ import annotations

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
        raise ValueError(f"{what} topic must be a topic name starting with '/', got {pattern!r}")
    if "{i}" in pattern:
        return [pattern.replace("{i}", str(i)) for i in range(N_SONAR)]
    return [pattern]


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


def _saturate(values_m: np.ndarray, low: float, high: float) -> np.ndarray:
    cm = np.asarray(values_m, dtype=np.float64) * 100.0
    cm = np.where(np.isposinf(cm), high, np.where(np.isneginf(cm), low, cm))
    return np.clip(cm, low, high)


def read_bag(
    path: str | Path,
    *,
    map: str | Path | None = None,
    sonar: str = SONAR_TOPIC,
    ir: str = IR_TOPIC,
    odometry: str = ODOMETRY_TOPIC,
    pose: str | None = None,
    pose_frame: str = "start",
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Positions ``(n, 2)`` cm in ``map``'s frame, readings ``(n, 32)`` cm and statistics of a bag's readings.

    ``sonar`` / ``ir``: a topic pattern with ``{i}`` (16 ``Range`` topics) or one ``LaserScan`` topic;
    ``odometry``: the ``Odometry`` topic, which is the pose source unless ``pose`` names another topic
    (module docstring).
    """
    frame = _check_frame(pose_frame)
    ring_topics(sonar, "sonar"), ring_topics(ir, "ir")  # checked before the bag is opened
    if not isinstance(odometry, str) or not odometry.startswith("/"):
        raise ValueError(f"odometry topic must be a topic name starting with '/', got {odometry!r}")
    pose_topic = odometry if pose is None else pose
    if not isinstance(pose_topic, str) or not pose_topic.startswith("/"):
        raise ValueError(f"pose topic must be a topic name starting with '/', got {pose!r}")
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
        if odometry not in types:
            raise ValueError(f"bag {name}: no odometry: no topic {odometry!r} (its topics: {topics})")
        for topic, expected in [
            (t, (RANGE,) if "{i}" in p else (SCAN,)) for p in (sonar, ir) for t in ring_topics(p, "")
        ]:
            if topic not in types:
                raise ValueError(f"bag {name}: no topic {topic!r} (its topics: {topics})")
            if types[topic] not in expected:
                raise ValueError(f"bag {name}: topic {topic!r} is {types[topic]}, expected {expected[0]}")
        if types[odometry] != ODOMETRY:
            raise ValueError(f"bag {name}: topic {odometry!r} is {types[odometry]}, expected {ODOMETRY}")
        if pose_topic not in types:
            raise ValueError(f"bag {name}: no pose topic {pose_topic!r} (its topics: {topics})")
        if types[pose_topic] not in POSE_TYPES:
            raise ValueError(
                f"bag {name}: topic {pose_topic!r} is {types[pose_topic]}, expected one of {', '.join(POSE_TYPES)}"
            )
        slots = {}  # topic -> first slot of the 32
        for ring, pattern in ((0, sonar), (N_SONAR, ir)):
            for j, topic in enumerate(ring_topics(pattern, "")):
                slots[topic] = ring + j
        wanted = [c for c in reader.connections if c.topic in slots or c.topic == pose_topic]
        current = np.full(N_SONAR + N_IR, np.nan)
        fresh = np.zeros(N_SONAR + N_IR, dtype=bool)
        last_pose: np.ndarray | None = None
        positions, readings, before_pose, poses = [], [], 0, 0
        for connection, _, raw in reader.messages(connections=wanted):
            msg = reader.deserialize(raw, connection.msgtype)
            topic = connection.topic
            if topic == pose_topic:
                inner = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
                last_pose = np.array([inner.position.x, inner.position.y])
                poses += 1
                if topic not in slots:
                    continue
            first = slots[topic]
            values = np.atleast_1d(np.asarray(msg.ranges if connection.msgtype == SCAN else msg.range, dtype=float))
            if connection.msgtype == SCAN and len(values) != N_SONAR:
                raise ValueError(f"bag {name}: LaserScan topic {topic!r} has {len(values)} ranges, expected {N_SONAR}")
            if np.isnan(values).any():
                raise ValueError(f"bag {name}: topic {topic!r} has a NaN range")
            span = slice(first, first + len(values))
            current[span] = _saturate(values, LOW_CM[first], HIGH_CM[first])
            fresh[span] = True
            if fresh.all():
                fresh[:] = False
                if last_pose is None:
                    before_pose += 1
                    continue
                positions.append(_to_map(last_pose, frame, start))
                readings.append(current.copy())
    finally:
        reader.close()
    if poses == 0:
        raise ValueError(f"bag {name}: no odometry: topic {pose_topic!r} has no messages")
    if not readings:
        raise ValueError(
            f"bag {name}: no complete reading (every one of the 32 sensors after a pose on {pose_topic!r})"
        )
    stats = {"readings": len(readings), "readings_before_first_pose": before_pose, "poses": poses}
    return np.array(positions), np.array(readings), stats


def import_bag(
    path: str | Path,
    *,
    map: str | Path | None = None,
    sonar: str = SONAR_TOPIC,
    ir: str = IR_TOPIC,
    odometry: str = ODOMETRY_TOPIC,
    pose: str | None = None,
    pose_frame: str = "start",
    per_cell: int | None = None,
    require_all_cells: bool = True,
    tolerance_cm: float = 5.0,
) -> SensorDatabase:
    """A database of ``map`` from a bag's readings (:func:`read_bag`), filed under lattice cells as the CSV import
    files them (:func:`~twodrl_envs.memorable.database.import_readings`: ``per_cell``, ``require_all_cells``,
    ``tolerance_cm``)."""
    positions, readings, stats = read_bag(
        path, map=map, sonar=sonar, ir=ir, odometry=odometry, pose=pose, pose_frame=pose_frame
    )
    recording = {
        "source": "ros2 bag",
        "file": Path(path).name,
        "topics": {"sonar": sonar, "ir": ir, "odometry": odometry, "pose": pose or odometry},
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
) -> Path:
    """Write a drive (positions ``(n, 2)`` cm in ``map``'s frame, readings ``(n, 32)`` cm) as a ROS 2 bag (``storage``
    ``"sqlite3"`` or ``"mcap"``),
    as a Nomad-like robot logs it: per reading, its odometry, then each sensor's ``Range`` (or each ring's
    ``LaserScan``), ``period_s`` apart; ranges at the sensors' maxima are ``+inf`` (REP 117)."""
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
    rosbags = import_rosbags()
    typestore = rosbags.typesys.get_typestore(rosbags.typesys.Stores.ROS2_HUMBLE)
    types = typestore.types
    start = office_core(map).office.start
    odometry_xy = _from_map(positions_cm, frame, start)

    def header(ns: int, frame_id: str) -> Any:
        stamp = types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)

    def range_msg(ns: int, value_cm: float, slot: int) -> Any:
        infrared = slot >= N_SONAR
        high = HIGH_CM[slot]
        return types[RANGE](
            header=header(ns, f"{'ir' if infrared else 'sonar'}_{slot % N_SONAR}"),
            radiation_type=1 if infrared else 0,
            field_of_view=0.0 if infrared else float(np.deg2rad(22.5)),
            min_range=float(LOW_CM[slot] / 100.0),
            max_range=float(high / 100.0),
            range=np.inf if value_cm >= high else float(value_cm / 100.0),
        )

    def scan_msg(ns: int, values_cm: np.ndarray, first: int) -> Any:
        high = HIGH_CM[first]
        return types[SCAN](
            header=header(ns, "sonar_ring" if first == 0 else "ir_ring"),
            angle_min=0.0,
            angle_max=float(np.deg2rad(22.5 * (N_SONAR - 1))),
            angle_increment=float(np.deg2rad(22.5)),
            time_increment=0.0,
            scan_time=0.0,
            range_min=float(LOW_CM[first] / 100.0),
            range_max=float(high / 100.0),
            ranges=np.where(values_cm >= high, np.inf, values_cm / 100.0).astype(np.float32),
            intensities=np.zeros(0, dtype=np.float32),
        )

    point, quaternion, vector = (types[f"geometry_msgs/msg/{t}"] for t in ("Point", "Quaternion", "Vector3"))
    path = Path(path)
    plugin = rosbags.rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbags.rosbag2.StoragePlugin.SQLITE3
    with rosbags.rosbag2.Writer(path, version=8, storage_plugin=plugin) as writer:
        odom = writer.add_connection(odometry, ODOMETRY, typestore=typestore)
        rings = []
        for first, pattern in ((0, sonar), (N_SONAR, ir)):
            topics = ring_topics(pattern, "sonar" if first == 0 else "ir")
            kind = RANGE if len(topics) > 1 else SCAN
            rings.append((first, kind, [writer.add_connection(t, kind, typestore=typestore) for t in topics]))
        for n, (xy, values) in enumerate(zip(odometry_xy, ranges_cm, strict=True)):
            ns = round(n * period_s * 1e9) + 10**9
            message = types[ODOMETRY](
                header=header(ns, "odom"),
                child_frame_id="base_link",
                pose=types["geometry_msgs/msg/PoseWithCovariance"](
                    pose=types["geometry_msgs/msg/Pose"](
                        position=point(x=float(xy[0]), y=float(xy[1]), z=0.0),
                        orientation=quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
                    ),
                    covariance=np.zeros(36),
                ),
                twist=types["geometry_msgs/msg/TwistWithCovariance"](
                    twist=types["geometry_msgs/msg/Twist"](
                        linear=vector(x=0.0, y=0.0, z=0.0), angular=vector(x=0.0, y=0.0, z=0.0)
                    ),
                    covariance=np.zeros(36),
                ),
            )
            writer.write(odom, ns, typestore.serialize_cdr(message, ODOMETRY))
            offset = 0
            for first, kind, connections in rings:
                for j, connection in enumerate(connections):
                    offset += 1000
                    if kind == RANGE:
                        msg = range_msg(ns + offset, float(values[first + j]), first + j)
                    else:
                        msg = scan_msg(ns + offset, values[first : first + N_SONAR], first)
                    writer.write(connection, ns + offset, typestore.serialize_cdr(msg, kind))
    return path
