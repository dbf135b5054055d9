"""Our messages <-> ROS 2 messages (rosbags' ROS 2 Jazzy typestore) and CDR bytes.

Pure functions, no transport. Used by the ROS 2 face and ``papf export ros2`` (ours -> ROS)
and ``papf report`` of a rosbag2 (ROS -> ours). Frames follow REP 105 (``odom`` our world,
``base_link``, ``laser``); stamps are our ``stamp_ns``. ROS's ``BatteryState.current`` is
negative while discharging (ours positive), NaN there means "not measured".
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from rosbags.typesys import Stores, get_typestore

from common import robot
from common.units import NS_PER_S as NS
from common.urdf import BASE_LINK, LASER
from schemas.messages import BatteryState, Odometry, PlannerState, Scan, Twist

STORE = Stores.ROS2_JAZZY
ODOM = "odom"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
TWIST = "geometry_msgs/msg/Twist"
BATTERY_STATE = "sensor_msgs/msg/BatteryState"
PATH = "nav_msgs/msg/Path"
MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
STRING = "std_msgs/msg/String"
PACK_CAPACITY_AH = robot.CELL_CAPACITY_MAH / 1000.0   # [Ah] 3 cells in series: one cell's
# The viewer's colours of the planner's mind (nodes/viewer/scene.MIND_COLOURS; a test keeps
# them equal), r g b a in 0..1, and the drawn sizes [m]; a plug-in's own debug values carry
# their own style (PlannerState.debug).
COLOURS = {"prediction": (0.42, 0.15, 0.75, 1.0), "temporary_goal": (0.09, 0.75, 0.81, 1.0),
           "force": (0.15, 0.15, 0.15, 1.0)}
TEMP_GOAL_DIAMETER_M = 0.16
FORCE_MIN_M, FORCE_MAX_M = 0.15, 0.8   # [m] drawn length of the force arrow (log-scaled |F|)
MARKER_NS = "mind"


@lru_cache(maxsize=1)
def typestore():
    """The ROS 2 Jazzy type store (built once; read-only afterwards).

    ``Stores.ROS2_JAZZY`` (rosbags >= 0.10 has it). The four types the robot bridge uses
    (:mod:`common.ros2`, Humble) have the same definitions and CDR in both. Frames: ``laser``
    is the LiDAR at its mount (:mod:`common.robot`, the URDF of :mod:`common.urdf`).
    """
    return get_typestore(STORE)


def _cls(typename: str):
    return typestore().types[typename]


def serialize(msg, typename: str) -> bytes:
    """A rosbags message -> CDR bytes (little endian, with the 4-byte encapsulation header)."""
    return bytes(typestore().serialize_cdr(msg, typename))


def deserialize(data: bytes | memoryview, typename: str):
    """CDR bytes -> a rosbags message of ``typename``."""
    return typestore().deserialize_cdr(bytes(data), typename)


# -- pieces ---------------------------------------------------------------------------------------
def time_msg(stamp_ns: int):
    """A builtin_interfaces/Time of ``stamp_ns`` [ns]."""
    sec, nanosec = divmod(int(stamp_ns), NS)
    return _cls("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)


def stamp_of(header) -> int:
    """Integer nanoseconds of a ``std_msgs/msg/Header``'s stamp."""
    return int(header.stamp.sec) * NS + int(header.stamp.nanosec)


def header(stamp_ns: int, frame_id: str):
    """A std_msgs/Header at ``stamp_ns`` [ns] in ``frame_id``."""
    return _cls("std_msgs/msg/Header")(stamp=time_msg(stamp_ns), frame_id=frame_id)


def quaternion(yaw: float):
    """The quaternion of a rotation by ``yaw`` [rad] about z."""
    return _cls("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=math.sin(0.5 * yaw),
                                                w=math.cos(0.5 * yaw))


def yaw_of(q) -> float:
    """Yaw [rad] of a quaternion (ZYX convention; roll and pitch ignored)."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _vec3(x: float = 0.0, y: float = 0.0, z: float = 0.0):
    return _cls("geometry_msgs/msg/Vector3")(x=float(x), y=float(y), z=float(z))


def _point(x: float = 0.0, y: float = 0.0, z: float = 0.0):
    return _cls("geometry_msgs/msg/Point")(x=float(x), y=float(y), z=float(z))


def _pose(x: float, y: float, yaw: float, z: float = 0.0):
    return _cls("geometry_msgs/msg/Pose")(position=_point(x, y, z), orientation=quaternion(yaw))


def _transform(stamp_ns: int, parent: str, child: str, x: float, y: float, z: float,
               yaw: float):
    tf = _cls("geometry_msgs/msg/Transform")(translation=_vec3(x, y, z), rotation=quaternion(yaw))
    return _cls("geometry_msgs/msg/TransformStamped")(header=header(stamp_ns, parent),
                                                      child_frame_id=child, transform=tf)


# -- ours -> ROS 2 --------------------------------------------------------------------------------
def laser_scan(scan: Scan, frame_id: str = LASER):
    """``sensor_msgs/msg/LaserScan`` of a scan; ranges as recorded (inf = no return)."""
    r = np.asarray(scan.ranges, dtype=np.float32)
    n = len(r)
    period = 1.0 / robot.LIDAR_RATE_HZ
    return _cls(LASER_SCAN)(
        header=header(scan.stamp_ns, frame_id), angle_min=float(scan.angle_min),
        angle_max=float(scan.angle_min + scan.angle_increment * max(n - 1, 0)),
        angle_increment=float(scan.angle_increment), time_increment=period / max(n, 1),
        scan_time=period, range_min=float(scan.range_min), range_max=float(scan.range_max),
        ranges=r, intensities=np.zeros(0, np.float32))


def odometry(odo: Odometry):
    """``nav_msgs/msg/Odometry``: pose in ``odom``, twist in ``base_link``, no covariance."""
    tw = _cls(TWIST)(linear=_vec3(x=odo.v), angular=_vec3(z=odo.w))
    cov = np.zeros(36, dtype=np.float64)
    return _cls(ODOMETRY)(
        header=header(odo.stamp_ns, ODOM), child_frame_id=BASE_LINK,
        pose=_cls("geometry_msgs/msg/PoseWithCovariance")(pose=_pose(odo.x, odo.y, odo.yaw),
                                                          covariance=cov),
        twist=_cls("geometry_msgs/msg/TwistWithCovariance")(twist=tw, covariance=cov.copy()))


def tf_odom(odo: Odometry):
    """``tf2_msgs/msg/TFMessage``: ``odom -> base_link`` at the odometry's pose."""
    return _cls(TF_MESSAGE)(transforms=[_transform(odo.stamp_ns, ODOM, BASE_LINK, odo.x, odo.y,
                                                   0.0, odo.yaw)])


def tf_static(stamp_ns: int = 0):
    """``tf2_msgs/msg/TFMessage``: ``base_link -> laser`` at the LiDAR's mount (common.robot)."""
    return _cls(TF_MESSAGE)(transforms=[_transform(
        stamp_ns, BASE_LINK, LASER, robot.LIDAR_X_M, robot.LIDAR_Y_M, robot.LIDAR_HEIGHT_M,
        robot.LIDAR_YAW_RAD)])


def twist(cmd: Twist):
    """``geometry_msgs/msg/Twist``: linear.x = v [m/s], angular.z = w [rad/s]."""
    return _cls(TWIST)(linear=_vec3(x=cmd.v), angular=_vec3(z=cmd.w))


def battery_state(b: BatteryState, frame_id: str = BASE_LINK):
    """``sensor_msgs/msg/BatteryState``; current negative while discharging (ROS convention),
    charge [Ah] = state of charge x the pack's capacity."""
    cls = _cls(BATTERY_STATE)
    status = (cls.POWER_SUPPLY_STATUS_DISCHARGING if b.current > 0
              else cls.POWER_SUPPLY_STATUS_NOT_CHARGING)
    return cls(header=header(b.stamp_ns, frame_id), voltage=float(b.voltage),
               temperature=math.nan, current=-float(b.current),
               charge=float(b.soc) * PACK_CAPACITY_AH, capacity=PACK_CAPACITY_AH,
               design_capacity=PACK_CAPACITY_AH, percentage=float(b.soc),
               power_supply_status=status, power_supply_health=cls.POWER_SUPPLY_HEALTH_UNKNOWN,
               power_supply_technology=cls.POWER_SUPPLY_TECHNOLOGY_LION, present=True,
               cell_voltage=np.zeros(0, np.float32), cell_temperature=np.zeros(0, np.float32),
               location="", serial_number=b.model)


def path(state: PlannerState, frame_id: str = ODOM):
    """``nav_msgs/msg/Path`` of the planner's predicted path; each pose faces the next point."""
    pts = [(float(p[0]), float(p[1])) for p in state.predicted_path]
    poses = []
    for i, (x, y) in enumerate(pts):
        a, b = (i, i + 1) if i + 1 < len(pts) else (i - 1, i)
        yaw = (math.atan2(pts[b][1] - pts[a][1], pts[b][0] - pts[a][0]) if a >= 0 else 0.0)
        poses.append(_cls("geometry_msgs/msg/PoseStamped")(header=header(state.stamp_ns, frame_id),
                                                           pose=_pose(x, y, yaw)))
    return _cls(PATH)(header=header(state.stamp_ns, frame_id), poses=poses)


def _marker(state: PlannerState, mid: int, kind: str, colour, width: float,
            points=(), z: float = 0.0, ns: str = MARKER_NS):
    """A marker of ``colour`` (a name of :data:`COLOURS`, or r, g, b, a)."""
    cls = _cls("visualization_msgs/msg/Marker")
    r, g, b, a = COLOURS[colour] if isinstance(colour, str) else colour
    return cls(header=header(state.stamp_ns, ODOM), ns=ns, id=mid, type=getattr(cls, kind),
               action=cls.ADD, pose=_pose(0.0, 0.0, 0.0), scale=_vec3(width, width, width),
               color=_cls("std_msgs/msg/ColorRGBA")(r=r, g=g, b=b, a=a),
               lifetime=_cls("builtin_interfaces/msg/Duration")(sec=0, nanosec=0),
               frame_locked=False, points=[_point(p[0], p[1], z) for p in points], colors=[],
               texture_resource="", texture=_cls("sensor_msgs/msg/CompressedImage")(
                   header=header(0, ""), format="", data=np.zeros(0, np.uint8)),
               uv_coordinates=[], text="", mesh_resource="",
               mesh_file=_cls("visualization_msgs/msg/MeshFile")(filename="",
                                                                 data=np.zeros(0, np.uint8)),
               mesh_use_embedded_materials=False)


def _force_points(state: PlannerState, robot_xy):
    fx, fy = state.force
    mag = math.hypot(fx, fy)
    if robot_xy is None or not (mag > 0 and math.isfinite(mag)):
        return None
    length = min(FORCE_MAX_M, FORCE_MIN_M + 0.15 * math.log1p(mag))
    x, y = robot_xy
    return [(x, y), (x + length * fx / mag, y + length * fy / mag)]


def markers(state: PlannerState, robot_xy: tuple[float, float] | None = None):
    """``visualization_msgs/msg/MarkerArray`` of the planner's mind this cycle, in ``odom``:
    DELETEALL first (the previous cycle goes), then the temporary goal and the force arrow at
    ``robot_xy`` (log-scaled length) in ``ns`` ``mind``, and the plug-in's own debug values
    by kind in their declared style, each in its own ``ns`` ``mind/<name>`` (RViz lists and
    hides them one by one): points as a SPHERE_LIST, paths one LINE_STRIP each, scalars and
    counts as text above the robot. Marker ids are stable by role."""
    cls = _cls("visualization_msgs/msg/Marker")
    clear = _marker(state, 0, "SPHERE_LIST", "temporary_goal", 0.0)
    clear.action = cls.DELETEALL
    out = [clear]
    if len(state.temporary_goal) >= 2:
        out.append(_marker(state, 2, "SPHERE_LIST", "temporary_goal", TEMP_GOAL_DIAMETER_M,
                           [tuple(state.temporary_goal[:2])], z=0.08))
    arrow = _force_points(state, robot_xy)
    if arrow is not None:
        m = _marker(state, 3, "ARROW", "force", 0.03, arrow, z=0.3)
        m.scale = _vec3(0.03, 0.06, 0.08)   # shaft diameter, head diameter, head length
        out.append(m)
    lines = 0
    for d in state.debug:
        ns = f"{MARKER_NS}/{d.name}"
        if d.kind in ("points", "point") and d.points:
            out.append(_marker(state, 0, "SPHERE_LIST", d.colour, d.size, d.points, z=0.1, ns=ns))
        elif d.kind == "paths":
            z = 0.02 if d.size < 0.035 else 0.05   # thin ones beneath the prediction
            out += [_marker(state, i, "LINE_STRIP", d.colour, d.size, p, z=z, ns=ns)
                    for i, p in enumerate(d.paths) if len(p) > 1]
        elif d.kind in ("scalar", "count") and not math.isnan(d.value) and robot_xy is not None:
            m = _marker(state, 0, "TEXT_VIEW_FACING", d.colour, 0.1, ns=ns)
            m.pose = _pose(robot_xy[0], robot_xy[1], 0.7 + 0.15 * lines)
            m.text = d.words()
            lines += 1
            out.append(m)
    return _cls(MARKER_ARRAY)(markers=out)


def string(text: str):
    """``std_msgs/msg/String`` (``/robot_description`` carries the URDF in one)."""
    return _cls(STRING)(data=text)


# -- ROS 2 -> ours --------------------------------------------------------------------------------
def odometry_of(msg, stamp_ns: int | None = None) -> Odometry:
    """Our planar :class:`Odometry` of a ``nav_msgs/msg/Odometry`` (stamp: its header's)."""
    p = msg.pose.pose
    return Odometry(stamp_ns=stamp_of(msg.header) if stamp_ns is None else stamp_ns,
                    x=float(p.position.x), y=float(p.position.y), yaw=yaw_of(p.orientation),
                    v=float(msg.twist.twist.linear.x), w=float(msg.twist.twist.angular.z))


def twist_of(msg, stamp_ns: int) -> Twist:
    """Our :class:`Twist` of a ``geometry_msgs/msg/Twist`` (it has no stamp: give one)."""
    return Twist(stamp_ns=stamp_ns, v=float(msg.linear.x), w=float(msg.angular.z))


def discharge_current_of(msg) -> float | None:
    """Current drawn from the pack [A], positive while discharging, of a
    ``sensor_msgs/msg/BatteryState``; None when it carries none (NaN or not finite)."""
    current = float(msg.current)
    return -current if math.isfinite(current) else None


def scan_of(msg, stamp_ns: int | None = None) -> Scan:
    """Our :class:`Scan` of a ``sensor_msgs/msg/LaserScan`` at the LiDAR's mount (common.robot);
    the geometry as the message gives it (no resampling)."""
    return Scan(stamp_ns=stamp_of(msg.header) if stamp_ns is None else stamp_ns,
                angle_min=float(msg.angle_min), angle_increment=float(msg.angle_increment),
                range_min=float(msg.range_min), range_max=float(msg.range_max),
                ranges=np.asarray(msg.ranges, dtype=np.float32), sensor_x=robot.LIDAR_X_M,
                sensor_y=robot.LIDAR_Y_M, sensor_yaw=robot.LIDAR_YAW_RAD)


# -- what RViz and Nav2 expect besides (the face, papf export ros2) ---------------------------
OCCUPANCY_GRID = "nav_msgs/msg/OccupancyGrid"
JOINT_STATE = "sensor_msgs/msg/JointState"
CLOCK = "rosgraph_msgs/msg/Clock"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
MAP = "map"


def occupancy_grid(grid, stamp_ns: int = 0, frame_id: str = MAP):
    """``nav_msgs/msg/OccupancyGrid`` of a :class:`worlds.maps.OccupancyMap` (row-major from
    the origin cell, -1 unknown, 0..100 occupied %), as Nav2's map_server publishes it."""
    rows, cols = grid.shape
    x0, y0, yaw = grid.origin
    info = _cls("nav_msgs/msg/MapMetaData")(
        map_load_time=time_msg(stamp_ns), resolution=float(grid.resolution), width=int(cols),
        height=int(rows), origin=_pose(float(x0), float(y0), float(yaw)))
    return _cls(OCCUPANCY_GRID)(header=header(stamp_ns, frame_id), info=info,
                                data=np.ascontiguousarray(grid.data, dtype=np.int8).ravel())


def tf_map_odom(stamp_ns: int):
    """``map -> odom``, the identity: our world frame is the map's (no localisation drift)."""
    return _transform(stamp_ns, MAP, ODOM, 0.0, 0.0, 0.0, 0.0)


def joint_state(stamp_ns: int, names, positions, velocities, efforts):
    """``sensor_msgs/msg/JointState`` of the wheel joints (rad, rad/s, N m)."""
    return _cls(JOINT_STATE)(header=header(stamp_ns, ""), name=list(names),
                             position=np.asarray(positions, np.float64),
                             velocity=np.asarray(velocities, np.float64),
                             effort=np.asarray(efforts, np.float64))


def wheel_transforms(stamp_ns: int, joints: dict[str, tuple[tuple[float, float, float], float]]):
    """``base_link -> <wheel>_link`` for each wheel: its joint's origin (x, y, z) [m] and its
    angle [rad] about the axle (y), what robot_state_publisher makes of ``/joint_states``."""
    out = []
    for child, ((x, y, z), angle) in joints.items():
        tf = _cls("geometry_msgs/msg/Transform")(
            translation=_vec3(x, y, z),
            rotation=_cls("geometry_msgs/msg/Quaternion")(x=0.0, y=math.sin(0.5 * angle), z=0.0,
                                                          w=math.cos(0.5 * angle)))
        out.append(_cls("geometry_msgs/msg/TransformStamped")(
            header=header(stamp_ns, BASE_LINK), child_frame_id=child, transform=tf))
    return out


def tf_message(transforms):
    """``tf2_msgs/msg/TFMessage`` of TransformStamped messages."""
    return _cls(TF_MESSAGE)(transforms=list(transforms))


def clock(stamp_ns: int):
    """``rosgraph_msgs/msg/Clock`` at ``stamp_ns`` (sim time: what ``use_sim_time`` nodes read)."""
    return _cls(CLOCK)(clock=time_msg(stamp_ns))


def diagnostics(stamp_ns: int, statuses):
    """``diagnostic_msgs/msg/DiagnosticArray`` of (name, level 0 OK/1 WARN/2 ERROR/3 STALE,
    message, {key: value}) tuples."""
    c = _cls("diagnostic_msgs/msg/DiagnosticStatus")
    kv = _cls("diagnostic_msgs/msg/KeyValue")
    out = [c(level=int(level), name=name, message=message, hardware_id="papf-stack",
             values=[kv(key=k, value=str(v)) for k, v in values.items()])
           for name, level, message, values in statuses]
    return _cls(DIAGNOSTIC_ARRAY)(header=header(stamp_ns, ""), status=out)
