"""`papf rosbot-emulator`: the ROSbot as seen through ``zenoh-bridge-ros2dds`` or rmw_zenoh, without a robot.

:class:`EmulatedRosbot` (pure) is a unicycle behind the ROSbot's own command limits and
timeout; :func:`run` takes ``cmd_vel`` and publishes odometry, battery and (with
``--world``) a scan as CDR on the bridge's keys or as an rmw_zenoh node. Used by
``papf rosbot-emulator`` and the robot-path tests and benches.
On the bridge it also answers the bridge's admin space for its node ``/rosbot_emulator``
(:mod:`papf.robot.bridge_admin`), so ``papf node list`` sees it as a real bridge's node.
"""

from __future__ import annotations

import argparse
import json
import math
import queue
import time

from common import ros2
from common.drive import CommandGate, RosbotLimits, unicycle
from common.errors import SchemaError
from common.outfiles import append_jsonl
from common.ros_link import BridgeTopics, cmd_vel_type, open_link, ros_domain
from common.transport import open_node, setup_logging
from nodes.base_driver.rosbot import ORIGIN, Pose2D, cdr_to_twist, compose
from schemas.messages import Event
from worlds import load_world

NAME = "rosbot_emulator"
ROS_NODE = "rosbot_emulator"        # its ROS 2 node name on rmw_zenoh
PUBLISHED = {"odometry": ros2.ODOMETRY, "battery": ros2.BATTERY_STATE, "scan": ros2.LASER_SCAN}
BATTERY_PERIOD_NS = 1_000_000_000   # [ns] /battery rate of the emulation: 1 Hz
SCAN_PERIOD_NS = 100_000_000        # [ns] RPLIDAR A3 at 10 Hz (docs/architecture.md "The robot")
NO_TIMEOUT_NS = 10**18              # "never": --cmd-timeout 0
CONTACT_GAP_NS = 200_000_000        # [ns] contact-free time that ends a contact episode (as the sim's)


class EmulatedRosbot:
    """Unicycle + the controller's command gate, stepped with wall-clock nanoseconds.

    The body (:class:`EmulatedRosbot`, pure) is a unicycle whose commands pass the robot's own
    ``diff_drive_controller`` behaviour: the ROSbot limits of
    :class:`common.drive.RosbotLimits` (clamp, 1.0 m/s², 4.0 rad/s²) and its
    ``cmd_vel_timeout`` (``--cmd-timeout``, 0.5 s; 0 disables it, to show that the base driver
    alone stops the robot). Odometry is exact (no slip, no noise) and starts at (0, 0, 0) like
    a freshly started EKF; with ``--world`` the robot really stands at the world's start pose
    and the scan is cast there with :mod:`nodes.lidar_sim.core` (``--scan-beams`` rays).
    Header stamps are wall-clock time, as ROS time is. ``--trace FILE`` appends one JSON line
    per command received (``{"t_ns": monotonic ns, "v": .., "w": ..}``) for latency benches.
    Liveliness: ``<ns>/alive/rosbot_emulator`` (``--namespace``, ours, not the bridge's).
    With ``--world`` the body also touches the world's obstacles: each contact during a run
    (``run_started`` .. ``run_ended`` on our ``<ns>/events``) is a ``collision`` event there,
    stamped on the run's clock, as the world simulator reports one (:class:`BodyContacts`).
    """

    def __init__(self, cmd_timeout_s: float = 0.5, start: Pose2D = ORIGIN):
        watchdog = int(round(cmd_timeout_s * 1e9)) if cmd_timeout_s > 0 else NO_TIMEOUT_NS
        self.gate = CommandGate(RosbotLimits(watchdog_ns=watchdog))
        self.start = start                          # where the odom frame's origin really is
        self.pose = ORIGIN                          # in the robot's odom frame
        self.v = self.w = 0.0
        self.commands = 0

    def command(self, v: float, w: float, t_ns: int) -> None:
        """Take a cmd_vel (``v`` [m/s], ``w`` [rad/s]) received at ``t_ns`` [ns]."""
        self.commands += 1
        self.gate.command(v, w, t_ns)

    def step(self, t_ns: int, dt_s: float) -> None:
        """Apply the gated command over ``dt_s`` (exact arc of constant v, w)."""
        self.v, self.w, _ = self.gate.output(t_ns, dt_s)
        x, y, yaw = unicycle(*self.pose, self.v, self.w, dt_s)
        self.pose = Pose2D(x, y, math.atan2(math.sin(yaw), math.cos(yaw)))

    @property
    def world_pose(self) -> Pose2D:
        """The robot's pose in the world (start composed with odometry): x, y [m], yaw [rad]."""
        return compose(self.start, self.pose)

    def odometry_cdr(self, stamp_ns: int) -> bytes:
        """The odometry at ``stamp_ns`` [ns] as CDR nav_msgs/Odometry."""
        x, y, yaw = self.pose
        return ros2.encode(ros2.odometry(stamp_ns, x, y, yaw, self.v, self.w), ros2.ODOMETRY)


class BodyContacts:
    """The emulated body against the world's obstacles (what the world simulator's physics reports
    as ``collision`` events): the ROSbot's footprint box (:mod:`common.robot`), sampled at
    its corners and edge midpoints, inside an obstacle's footprint = contact. One event per
    contact episode per obstacle; an episode ends after :data:`CONTACT_GAP_NS` without
    contact. Obstacles at their t = 0 pose (the emulator moves none)."""

    def __init__(self, world):
        from common.robot import BODY_LENGTH_M, BODY_WIDTH_M

        self.obstacles = world.obstacles_at(0.0)
        hx, hy = BODY_LENGTH_M / 2.0, BODY_WIDTH_M / 2.0
        self.corners = [(sx * hx, sy * hy) for sx in (-1, 0, 1) for sy in (-1, 0, 1)
                        if (sx, sy) != (0, 0)]
        self.last_contact: dict[int, int] = {}      # obstacle index -> t_ns of its last contact

    def check(self, pose: Pose2D, t_ns: int) -> list[str]:
        """Obstacles whose contact episode begins at ``t_ns`` (their descriptions)."""
        import numpy as np

        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        pts = np.array([(pose.x + c * dx - s * dy, pose.y + s * dx + c * dy)
                        for dx, dy in self.corners])
        new = []
        for i, ob in enumerate(self.obstacles):
            if float(np.min(ob.model.distance(ob, pts))) >= 0.0:
                continue
            last = self.last_contact.get(i)
            if last is None or t_ns - last > CONTACT_GAP_NS:
                new.append(f"obstacle {i} ({ob.kind})")
            self.last_contact[i] = t_ns
        return new


class RunClock:
    """The run's clock as the robot side keeps it: 0 at ``run_started`` (as the rosbot
    driver's), None between runs; set from Zenoh's thread."""

    def __init__(self):
        self.t0: int | None = None

    def on_event(self, msg) -> None:
        if msg.kind == "run_started":
            self.t0 = time.monotonic_ns()
        elif msg.kind == "run_ended":
            self.t0 = None


def _lidar(args):
    if not args.world or args.no_scan:
        return None
    from nodes.lidar_sim.core import LidarParams, LidarSim  # pybullet: only when scanning

    return LidarSim(load_world(args.world), LidarParams(beams=args.scan_beams), args.seed)


def run(args: argparse.Namespace) -> int:
    """``papf rosbot-emulator`` (options: :mod:`papf.cli.emulator`) until SIGINT/SIGTERM.

    What a driver sees of the real robot (docs/architecture.md "The robot"), on the bridge keys
    ``[<bridge-ns>/]<topic>`` (``--ros bridge``, the default) or as the ROS 2 node
    ``/rosbot_emulator`` on rmw_zenoh (``--ros rmw_zenoh --ros-domain N``: rmw_zenoh's keys,
    liveliness tokens and attachments, :mod:`common.ros_link`), all CDR with the encapsulation
    header (``cmd_vel`` is ``TwistStamped`` with ``--cmd-vel-type twist_stamped``):

    =======================  ===========================  ===  ==================================
    key                      type                         dir  what
    =======================  ===========================  ===  ==================================
    ``cmd_vel``              geometry_msgs/Twist          in   linear.x, angular.z
    ``odometry/filtered``    nav_msgs/Odometry            out  ``--rate`` Hz (50), odom frame
    ``battery``              sensor_msgs/BatteryState     out  1 Hz, voltage only
    ``scan``                 sensor_msgs/LaserScan        out  10 Hz, only with ``--world``
    =======================  ===========================  ===  ==================================
    """
    log = setup_logging("emulator", args.log_level)
    topics = BridgeTopics(args.bridge_namespace)
    if getattr(args, "ros", "bridge") == "bridge":
        topics.check_separate(args.namespace)
    ros_domain(args)                       # a bad domain: exit 2 before any session opens
    cmd_type = cmd_vel_type(args)
    start = Pose2D(*load_world(args.world).start) if args.world else ORIGIN
    robot = EmulatedRosbot(args.cmd_timeout, start)
    lidar = _lidar(args)
    contacts = BodyContacts(load_world(args.world)) if args.world else None
    # line-buffered: the trace can be read while the emulator runs (tests, a live tail -f)
    trace = append_jsonl(args.trace) if args.trace else None   # JSON lines only, never a link
    with open_node(NAME, args, log) as node:
        link = open_link(args, node.session, ROS_NODE, topics.namespace)
        link.subscribe(topics.cmd_vel, cmd_type,
                       lambda data: node.inbox.put((time.monotonic_ns(), data)))
        pubs = {t: link.publisher(getattr(topics, t), typename) for t, typename in PUBLISHED.items()}
        clock = RunClock()
        if contacts is not None:   # collisions go on our bus, stamped on the run's clock
            node.subscribe("events", handler=clock.on_event)
            node.declare_publishers("events")
        admin = _bridge_admin(node.session, topics, cmd_type, lidar) if link.middleware == "bridge" \
            else None
        node.ready()
        log.info("emulating the ROSbot over %s: cmd_vel %s (%s); %s (scan: %s)", link.middleware,
                 link.key(topics.cmd_vel, cmd_type), cmd_type,
                 {t: link.key(getattr(topics, t), ty) for t, ty in PUBLISHED.items()},
                 "yes" if lidar else "no")
        try:
            _loop(node, robot, pubs, lidar, trace, args, cmd_type, log,
                  lambda now: _report_contacts(node, contacts, clock, robot, now, log))
        finally:
            link.close()
            if admin is not None:
                admin.close()
            if trace:
                trace.close()
            if lidar is not None:
                lidar.close()
            log.info("stopped after %d commands; odom pose %s", robot.commands, robot.pose)
    return 0


def _report_contacts(node, contacts: BodyContacts | None, clock: RunClock, robot: EmulatedRosbot,
                     now_ns: int, log) -> None:
    """A ``collision`` event per new contact episode during a run (none between runs)."""
    t0 = clock.t0
    if contacts is None or t0 is None:
        return
    pose = robot.world_pose
    for what in contacts.check(pose, now_ns):
        log.warning("collision with %s at (%.2f, %.2f)", what, pose.x, pose.y)
        node.publish("events", Event(stamp_ns=max(0, now_ns - t0), kind="collision", source=NAME,
                                     detail=what, x=pose.x, y=pose.y))


def _loop(node, robot: EmulatedRosbot, pubs, lidar, trace, args, cmd_type: str, log,
          after_step=lambda now: None) -> None:
    """Take commands, step the body at ``--rate`` Hz, publish odometry, battery and scan."""
    period = int(round(1e9 / args.rate))
    now = last = time.monotonic_ns()
    next_battery = next_scan = now
    while not node.stop:
        try:
            t_rx, data = node.inbox.get(timeout=max(0.0, (last + period - now) * 1e-9))
            if data is None:      # the stop request's wake-up (node.stop), not a command
                continue
            try:
                v, w = cdr_to_twist(data, cmd_type)
            except SchemaError as exc:
                log.warning("dropped bad cmd_vel: %s", exc)
            else:
                robot.command(v, w, t_rx)
                if trace:
                    trace.write(json.dumps({"t_ns": t_rx, "v": v, "w": w}) + "\n")
        except queue.Empty:
            pass
        now = time.monotonic_ns()
        if now - last < period:
            continue
        robot.step(now, (now - last) * 1e-9)
        after_step(now)
        last, wall = now, time.time_ns()
        pubs["odometry"].put(robot.odometry_cdr(wall))
        if now >= next_battery:
            next_battery = now + BATTERY_PERIOD_NS
            pubs["battery"].put(ros2.encode(ros2.battery_state(wall, args.battery_voltage),
                                            ros2.BATTERY_STATE))
        if lidar is not None and now >= next_scan:
            next_scan = now + SCAN_PERIOD_NS
            pubs["scan"].put(_scan_cdr(lidar, robot.world_pose, wall))


def _bridge_admin(session, topics: BridgeTopics, cmd_type: str, lidar):
    """Answer the bridge's admin space for our node: the topics as their ROS names."""
    from papf.robot.bridge_admin import BridgeAdmin

    published = {f"/{getattr(topics, t).strip('/')}": ty for t, ty in PUBLISHED.items()
                 if t != "scan" or lidar is not None}
    return BridgeAdmin(session, ROS_NODE, published, {f"/{topics.cmd_vel.strip('/')}": cmd_type})


def _scan_cdr(lidar, pose: Pose2D, wall_ns: int) -> bytes:
    scan = lidar.scan(pose.x, pose.y, pose.yaw, wall_ns)
    return ros2.encode(ros2.laser_scan(wall_ns, scan.angle_min, scan.angle_increment,
                                       scan.range_min, scan.range_max, scan.ranges),
                       ros2.LASER_SCAN)
