"""The LiDAR source node: ``python -m nodes.lidar_sim --world W --seed N ...`` (simulated) or
``--source ros2`` (the robot's real RPLIDAR).

Simulated, it casts an RPLIDAR A3 scan (:mod:`nodes.lidar_sim.core`) at the robot pose of each
scan instant: when a pose arrives whose stamp is due (``stamp >= next_due``, the
next multiple of the scan period; on the lockstep grid exactly ``stamp % period == 0``),
it publishes ``scan`` with that stamp. A pose stamp going backwards (a new run)
restarts the schedule. ``--source ros2`` hands over to the real sensor
(:mod:`nodes.lidar_sim.ros2_source`: the robot's ``LaserScan`` as our ``scan``).

Ports: :mod:`nodes.lidar_sim.ports` (``--help`` prints them).

Moving obstacles are placed at each scan's sim time. In a fleet (``[[robots]]`` or
``[[people]]`` in the world) each scan waits for ``sim/bodies`` of its instant too and
sees the other robots and the people there. With ``--truth-objects`` the node
also publishes the ground truth (pose, velocity, size of every obstacle, person and other
robot within the LiDAR's range) as ``Objects`` with the scan's stamp, just before the scan: the sim's
answer to ``--objects truth`` (also in HIL, for the virtual obstacles).

One process may serve a whole fleet (``--robots r1,r2,...``, names of the world's
``[[robots]]``; the launch profile's ``fleet = "one"``): one pybullet world holding every
robot's box, each robot's ``sim/pose`` and ``sim/bodies`` taken on its own namespace and its
``scan`` (and ``objects``) put there, its token ``<robot>/alive/lidar_sim`` — the same
messages, bit for bit, as a LiDAR process per robot, without a process, a session and a copy
of the world per robot.

Settings: ``--world``, ``--seed`` (noise), ``--beams`` (300), ``--scan-hz`` (10),
``--noise-sd`` (0.01 m), ``--noise-rel`` (0), ``--pose-source sim|odom``,
``--truth-objects``, ``--robots``, plus the Zenoh options. Liveliness token:
``<ns>/alive/lidar_sim``.
"""

from __future__ import annotations

import argparse
import sys

from common.cliparse import ArgumentParser
from common.errors import ConfigError, PapfError
from common.params import arg_type
from common.ports import describe, plain
from common.transport import Node, add_zenoh_args, exit_fast, open_node, setup_logging
from common.units import period_ns  # the time grid's one rate-to-period rule (the world sim's too)
from nodes.lidar_sim.options import OPTIONS
from nodes.lidar_sim.ports import EXTRAS, PORTS, VARIANTS
from schemas import Keys
from worlds import load_world
from worlds.messages import truth_objects

NAME = "lidar_sim"


class ScanSchedule:
    """Which pose stamps get a scan: the first one at or after each multiple of the period."""

    def __init__(self, period: int):
        self.period = period
        self.next_due = 0
        self.last = -1

    def due(self, stamp_ns: int) -> bool:
        if stamp_ns < self.last:          # the clock restarted: a new run
            self.next_due = 0
        self.last = stamp_ns
        if stamp_ns < self.next_due:
            return False
        self.next_due = (stamp_ns // self.period + 1) * self.period
        return True


class BodyPairs:
    """Pairs each due pose with the ``sim/bodies`` of its stamp, whichever comes first
    (they travel on different keys): a fleet's scan is cast only with both."""

    def __init__(self):
        self.poses: dict[int, object] = {}
        self.bodies: dict[int, object] = {}

    def add(self, topic: str, msg) -> tuple[object, object]:
        """Take a pose or bodies message; (pose, bodies) of a complete stamp, else (None, None)."""
        book = self.bodies if topic == "sim/bodies" else self.poses
        if any(t > msg.stamp_ns for t in book):   # the clock restarted: a new run
            self.poses.clear()
            self.bodies.clear()
        book[msg.stamp_ns] = msg
        t = msg.stamp_ns
        if t in self.poses and t in self.bodies:
            pose, bodies = self.poses.pop(t), self.bodies.pop(t)
            for old in [s for s in self.poses if s < t]:
                del self.poses[old]
            for old in [s for s in self.bodies if s < t]:
                del self.bodies[old]
            return pose, bodies
        return None, None


def main_sim(args: argparse.Namespace) -> int:
    from nodes.lidar_sim.core import LidarParams, LidarSim  # pybullet: only when simulating

    log = setup_logging(NAME, args.log_level)
    world = load_world(args.world)
    params = LidarParams(beams=args.beams, noise_sd=args.noise_sd, noise_rel=args.noise_rel)
    period = period_ns(args.scan_hz, "scan rate")
    fleet = [r.name for r in world.robots]
    if args.robots:
        return main_fleet(args, world, params, period, log)
    schedule = ScanSchedule(period)
    pose_topic = "sim/pose" if args.pose_source == "sim" else "odom"
    robot = fleet.index(args.namespace) if args.namespace in fleet else 0
    with LidarSim(world, params, args.seed, robot) as lidar, open_node(NAME, args, log) as node:
        def keep_due(pose) -> None:  # Zenoh's callback thread: only due poses wake the main one
            if schedule.due(pose.stamp_ns):
                node.inbox.put((pose_topic, pose))

        node.subscribe(pose_topic, handler=keep_due)
        pairs = BodyPairs() if (world.robots or world.has_people) else None
        if pairs is not None:   # a fleet: the others' bodies of each scan instant
            node.subscribe("sim/bodies")
        node.declare_publishers("scan", *(("objects",) if args.truth_objects else ()))
        node.ready()
        count = 0
        for topic, msg in node.messages():
            if topic is None:
                continue
            pose, bodies = msg, None
            if pairs is not None:
                pose, bodies = pairs.add(topic, msg)
                if pose is None:
                    continue
                lidar.place_bodies(bodies)
            if args.truth_objects:
                node.publish("objects", truth_objects(world, pose.stamp_ns, (pose.x, pose.y),
                                                      params.range_max, bodies))
            node.publish("scan", lidar.scan(pose.x, pose.y, pose.yaw, pose.stamp_ns))
            count += 1
        log.info("published %d scans", count)
    return 0


def robots_of(args: argparse.Namespace, world) -> list[str]:
    """``--robots`` checked against the world's ``[[robots]]`` (ConfigError: one line)."""
    names = [n for n in args.robots.split(",") if n]
    fleet = [r.name for r in world.robots]
    unknown = [n for n in names if n not in fleet]
    if unknown or not names or len(set(names)) != len(names):
        raise ConfigError(f"--robots {args.robots!r}: names of the world's robots, each once; "
                          f"{world.name!r} has {', '.join(fleet) or 'none'}")
    if args.pose_source != "sim":
        raise ConfigError("--robots (the sim's fleet) scans from the ground truth: no "
                          "--pose-source odom")
    return names


def main_fleet(args: argparse.Namespace, world, params, period: int, log) -> int:
    """One process for the fleet's LiDARs (module doc): each robot's share a :class:`Node`
    on this session under its namespace; its poses and bodies queued to this node's inbox as
    ``<robot>/<topic>``, each scan cast in the one world as its messages complete."""
    from nodes.lidar_sim.core import LidarSim

    names = robots_of(args, world)
    index = {r.name: i for i, r in enumerate(world.robots)}   # each robot's noise: its index
    objects = ("objects",) if args.truth_objects else ()
    with LidarSim(world, params, args.seed, fleet=tuple(index)) as lidar, \
            open_node(NAME, args, log) as node:
        shares, pairs = {}, {}
        for name in names:
            share = shares[name] = Node(NAME, node.session, Keys(name), log)
            schedule, pairs[name] = ScanSchedule(period), BodyPairs()

            def keep_due(pose, schedule=schedule, topic=f"{name}/sim/pose") -> None:
                if schedule.due(pose.stamp_ns):   # Zenoh's thread: only due poses wake us
                    node.inbox.put((topic, pose))

            share.subscribe("sim/pose", handler=keep_due)
            share.subscribe("sim/bodies",
                            handler=lambda m, t=f"{name}/sim/bodies": node.inbox.put((t, m)))
            share.declare_publishers("scan", *objects)
        for share in shares.values():
            share.ready()
        node.ready()   # <namespace>/alive/lidar_sim too: the process itself is up
        count = 0
        for topic, msg in node.messages():
            if topic is None:
                continue
            name, _, suffix = topic.partition("/")
            pose, bodies = pairs[name].add(suffix, msg)
            if pose is None:
                continue
            lidar.place_bodies(bodies)   # the others where they are, this robot's box parked
            if args.truth_objects:
                shares[name].publish("objects", truth_objects(
                    world, pose.stamp_ns, (pose.x, pose.y), params.range_max, bodies))
            shares[name].publish("scan", lidar.scan(pose.x, pose.y, pose.yaw, pose.stamp_ns,
                                                    robot=index[name]))
            count += 1
        log.info("published %d scans for %d robots", count, len(names))
        for share in shares.values():
            share.close()
    return 0


def main_ros2(args: argparse.Namespace) -> int:
    from nodes.lidar_sim import ros2_source  # imported only when asked: it pulls in rosbags

    return ros2_source.main(args) or 0


def _opt(name: str):
    return arg_type("--" + name.replace("_", "-"), OPTIONS[name])


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="python -m nodes.lidar_sim",
                                     description=plain(__doc__.split("\n\n")[0]),
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=plain(__doc__.split("\n\n", 1)[1]) + "\n"
                                     + describe(PORTS, VARIANTS, EXTRAS))
    parser.add_argument("--source", choices=("sim", "ros2"), default="sim",
                        help="simulated scans (default) or the real RPLIDAR over the ROS 2 bridge")
    parser.add_argument("--world", default="energy", help="world name or .toml path (sim)")
    parser.add_argument("--seed", type=_opt("seed"),
                        default=0, help="noise seed (default 0)")
    parser.add_argument("--beams", type=_opt("beams"),
                        default=300, help="rays per revolution (300)")
    parser.add_argument("--scan-hz", type=_opt("scan_hz"),
                        default=10.0, help="scan rate in sim time (10)")
    parser.add_argument("--noise-sd", type=_opt("noise_sd"),
                        default=0.01, metavar="M",
                        help="range noise sigma, constant part [m] (default 0.01)")
    parser.add_argument("--noise-rel", type=_opt("noise_rel"),
                        default=0.0, metavar="F",
                        help="range noise sigma, part proportional to the range (default 0)")
    parser.add_argument("--pose-source", choices=("sim", "odom"), default="sim",
                        help="pose to scan from: ground truth sim/pose (default) or odom")
    parser.add_argument("--truth-objects", action="store_true",
                        help="also publish the obstacles' ground truth on <ns>/objects (sim)")
    parser.add_argument("--robots", metavar="R1,R2,...",
                        help="one process for these robots of the world's [[robots]], each on "
                             "its own namespace (sim)")
    parser.add_argument("--log-level", default="INFO")
    add_zenoh_args(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--source", default="sim")
    known, _ = pre.parse_known_args(argv)
    parser = build_parser()
    if known.source == "ros2":  # the ROS 2 source's own options (bridge keys, sensor pose)
        from nodes.lidar_sim import ros2_source

        ros2_source.add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return main_ros2(args) if args.source == "ros2" else main_sim(args)
    except PapfError as exc:
        print(f"lidar_sim: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    exit_fast(main())   # the session is closed: skip the interpreter's slow teardown
