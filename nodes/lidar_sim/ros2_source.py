"""The LiDAR's real source, the robot's RPLIDAR, as our ``Scan``: ``python -m nodes.lidar_sim --source ros2 [--ros rmw_zenoh]``.

Reads ``sensor_msgs/LaserScan`` CDR from the bridge key ``[<bridge-ns>/]scan`` (the ROSbot's
``rplidar_ros``/``sllidar_ros2`` through ``zenoh-bridge-ros2dds``, docs/architecture.md "The
robot"), or with ``--ros rmw_zenoh --ros-domain N`` from rmw_zenoh's key of ``/scan`` as the
ROS 2 node ``/papf_lidar`` (:mod:`common.ros_link`), and publishes
``<ns>/scan``: the same 360° geometry as the simulated LiDAR (``--beams`` rays from -π,
2π/L apart; L = 300 by default, the paper's Table 1), so planners cannot tell the two apart.
Liveliness: ``<ns>/alive/lidar_sim``.

Readings (:func:`classify`): a finite range within [range_min, range_max] is a return;
``+inf``, ``-inf``, 0 (the A3's "no measurement", which ``rplidar_ros`` normally already
turns into ``inf``), anything below range_min or above range_max -> ``inf`` (no usable
return, as the simulated LiDAR reports it); ``NaN`` stays ``NaN`` (invalid).
Resampling (:func:`resample`): each output beam takes the nearest return among the source
readings that fall in its angular bin (conservative: the closest obstacle wins); a bin with
no return is ``inf`` if one of its readings said "no return", else ``NaN``; a bin no source
reading falls in (a coarser scan) takes the nearest source reading; a bin outside the
scanned field of view is ``NaN``.

Stamps: our scans carry the run time of the base driver's ``clock`` (latest clock + wall
time since it arrived); with no clock in the last second (no run, or no driver), scans are
not published.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from common import robot, ros2
from common.errors import SchemaError
from common.ros_link import BridgeTopics, add_ros_args, open_link, ros_domain
from schemas import Scan

NAME = "lidar_sim"
ROS_NODE = "papf_lidar"            # our ROS 2 node name on rmw_zenoh
TWO_PI = 2.0 * math.pi
CLOCK_TIMEOUT_NS = 1_000_000_000   # [ns] no driver clock for this long: do not publish scans
# Sensor pose in the robot frame: the mount assumed in common.robot (as the simulated LiDAR);
# on a real robot set it from TF (``ros2 run tf2_ros tf2_echo base_link laser``).
SENSOR_X, SENSOR_Y, SENSOR_YAW = robot.LIDAR_X_M, robot.LIDAR_Y_M, robot.LIDAR_YAW_RAD  # m, m, rad


def classify(ranges: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
    """float64 ranges with every non-return as ``inf`` and invalid readings as ``NaN``."""
    r = np.asarray(ranges, dtype=np.float64)
    out = np.where((r >= range_min) & (r <= range_max), r, np.inf)
    out[np.isnan(r)] = np.nan
    return out


def resample(ranges, angle_min: float, angle_increment: float, range_min: float,
             range_max: float, beams: int) -> np.ndarray:
    """Source readings -> ``beams`` float32 ranges at -π + j 2π/beams (see module doc)."""
    r = classify(ranges, range_min, range_max)
    n = len(r)
    if n == 0 or not (math.isfinite(angle_min) and math.isfinite(angle_increment)) \
            or angle_increment == 0.0:
        raise SchemaError(f"LaserScan with {n} ranges, angle_min={angle_min!r}, "
                          f"angle_increment={angle_increment!r}: need >= 1 range and a finite, "
                          "non-zero increment")
    if angle_increment < 0:          # clockwise scan: read it backwards
        angle_min, angle_increment, r = angle_min + angle_increment * (n - 1), -angle_increment, r[::-1]
    out_inc = TWO_PI / beams
    src_angles = angle_min + angle_increment * np.arange(n)
    bins = np.floor((src_angles + math.pi) / out_inc + 0.5).astype(np.int64) % beams
    ret, none = np.isfinite(r), np.isinf(r)
    best = np.full(beams, np.inf)
    np.minimum.at(best, bins[ret], r[ret])
    has = [np.bincount(bins[m], minlength=beams) > 0 for m in (ret, none, np.ones(n, bool))]
    out = np.where(has[0], best, np.where(has[1], np.inf, np.nan))
    empty = np.flatnonzero(~has[2])
    if empty.size:
        offset = (-math.pi + out_inc * empty - angle_min) % TWO_PI
        k = np.round(offset / angle_increment).astype(np.int64)
        if n * angle_increment >= TWO_PI * (1 - 1e-6):
            k %= n
        inside = k < n
        out[empty[inside]] = r[k[inside]]
        out[empty[~inside]] = np.nan
    return out.astype(np.float32)


def laserscan_to_scan(data: bytes, stamp_ns: int, beams: int = 300, sensor_x: float = SENSOR_X,
                      sensor_y: float = SENSOR_Y, sensor_yaw: float = SENSOR_YAW) -> Scan:
    """CDR ``sensor_msgs/LaserScan`` -> our :class:`~schemas.Scan` of ``beams`` rays at ``stamp_ns``."""
    msg = ros2.decode(data, ros2.LASER_SCAN)
    rmin, rmax = float(msg.range_min), float(msg.range_max)
    if not (0.0 <= rmin < rmax and math.isfinite(rmax)):
        raise SchemaError(f"LaserScan range_min={rmin!r}, range_max={rmax!r}: need "
                          "0 <= range_min < range_max < inf")
    ranges = resample(msg.ranges, float(msg.angle_min), float(msg.angle_increment), rmin, rmax,
                      beams)
    return Scan(stamp_ns=stamp_ns, angle_min=-math.pi, angle_increment=TWO_PI / beams,
                range_min=rmin, range_max=rmax, ranges=ranges, sensor_x=sensor_x,
                sensor_y=sensor_y, sensor_yaw=sensor_yaw)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``--source ros2`` (called by ``nodes.lidar_sim.__main__``)."""
    g = parser.add_argument_group("ROS 2 LiDAR source (--source ros2)")
    g.add_argument("--bridge-namespace", default="", metavar="NS",
                   help="zenoh-bridge-ros2dds namespace of the robot's topics (default: none)")
    g.add_argument("--bridge-scan", default="scan", metavar="TOPIC", help="(scan)")
    g.add_argument("--sensor-x", type=float, default=SENSOR_X, help="[m] laser in base_link")
    g.add_argument("--sensor-y", type=float, default=SENSOR_Y, help="[m]")
    g.add_argument("--sensor-yaw", type=float, default=SENSOR_YAW, help="[rad]")
    add_ros_args(parser, cmd_vel=False)


def main(args: argparse.Namespace) -> int:
    from common.transport import open_node, setup_logging

    log = setup_logging(NAME, getattr(args, "log_level", "INFO"))
    topics = BridgeTopics(getattr(args, "bridge_namespace", ""),
                          scan=getattr(args, "bridge_scan", "scan"))
    if getattr(args, "ros", "bridge") == "bridge":
        topics.check_separate(args.namespace)
    ros_domain(args)                       # a bad domain: exit 2 before any session opens
    sensor = (getattr(args, "sensor_x", SENSOR_X), getattr(args, "sensor_y", SENSOR_Y),
              getattr(args, "sensor_yaw", SENSOR_YAW))
    clock = None                        # (run time ns, monotonic ns it arrived)
    published = bad = 0
    with open_node(NAME, args, log) as node:
        node.subscribe("clock")
        link = open_link(args, node.session, ROS_NODE, topics.namespace)
        link.subscribe(topics.scan, ros2.LASER_SCAN, lambda data: node.inbox.put(("ros2_scan", data)))
        key = link.key(topics.scan, ros2.LASER_SCAN)
        node.declare_publishers("scan")
        node.ready()
        log.info("LaserScan from %s -> %s (%d beams)", key, node.keys.scan, args.beams)
        try:
            for topic, msg in node.messages():
                now = time.monotonic_ns()
                if topic == "clock":
                    clock = (msg.stamp_ns, now)
                elif topic == "ros2_scan" and clock and now - clock[1] <= CLOCK_TIMEOUT_NS:
                    try:
                        scan = laserscan_to_scan(msg, clock[0] + now - clock[1], args.beams, *sensor)
                    except SchemaError as exc:
                        bad += 1
                        if bad <= 5 or bad % 100 == 0:
                            log.warning("dropped bad LaserScan #%d on %s: %s", bad, key, exc)
                        continue
                    node.publish("scan", scan)
                    published += 1
        finally:
            link.close()
            log.info("published %d scans (%d bad LaserScans dropped)", published, bad)
    return 0
