"""Real-ROSbot base driver: ``python -m nodes.base_driver --driver rosbot [--ros rmw_zenoh]``.

The same node contract as the world simulator (``nodes/world_sim``: liveliness ``<ns>/alive/base_driver``),
talking to the robot through ``zenoh-bridge-ros2dds`` (``--ros bridge``, the default) or as
the ROS 2 node ``/papf_base_driver`` on rmw_zenoh (``--ros rmw_zenoh --ros-domain N``:
rmw_zenoh's keys, liveliness tokens and attachments, :mod:`common.ros_link`);
docs/architecture.md "The robot". Always real time. ``--cmd-vel-type twist_stamped`` sends
``geometry_msgs/TwistStamped`` (Jazzy's diff-drive controller) instead of ``Twist``.

Ports (``<ns>`` = ``--namespace``; ``<b>/`` = ``--bridge-namespace`` + ``/``, empty by
default; on rmw_zenoh ``<b>/t`` is the key of ROS topic ``/<bridge-namespace>/t``):

==========================  ====================  ===  ========================================
key                         type                  dir  what
==========================  ====================  ===  ========================================
``<ns>/cmd_vel``            Twist                 in   our command; clamped, rate-limited, watchdog
``<ns>/events``             Event                 in   ``run_started`` starts the clock at 0,
                                                       ``run_ended`` stops it (and the robot)
``<b>/cmd_vel``             CDR geometry_msgs/    out  the gated command, on every command and
                            Twist                      every tick; zeros for 1 s after a stop
``<b>/odometry/filtered``   CDR nav_msgs/         in   the robot's EKF odometry
                            Odometry
``<b>/battery``             CDR sensor_msgs/      in   pack voltage
                            BatteryState
``<ns>/odom``               Odometry              out  robot odometry in the run's world frame,
                                                       every tick while a run is on, 10 Hz between runs
``<ns>/wheels``             WheelStates           out  derived from odometry (rosbot.wheel_states)
``<ns>/clock``              Clock                 out  run time: wall time since ``run_started``
``<ns>/battery/measured``   BatteryVoltage        out  the robot's voltage (``info`` Event with
                                                       ``battery_voltage_V=`` if the schema lacks it)
``<ns>/events``             Event                 out  ``watchdog_stop``, ``node_fault`` (odometry lost)
==========================  ====================  ===  ========================================

Time: the driver owns the clock here too. A run's time is wall time since the driver saw
``run_started``, on a tick grid of ``--odom-hz`` (default 50 Hz: 20 ms), and every
odom/wheels/clock of a tick carries the same stamp. Between runs only ``odom`` is published,
at :data:`IDLE_ODOM_HZ`, stamped on from the last run's last tick (0 before the first run), so
that ``papf teleop`` shows where the robot is; commands are forwarded (with limits and
watchdog) at any time. During a run,
a command whose stamp (the scan it answers) is older than the watchdog is dropped as late:
after a network outage TCP delivers queued commands in a burst, and they are stale.
Odometry: at ``run_started`` the robot's current pose becomes the world's start pose
(``--world``'s ``robot.start``), see :class:`nodes.base_driver.rosbot.OdomFrame`; robot
odometry older than 0.5 s is not republished (the planner then stops on stale odometry).
"""

from __future__ import annotations

import argparse
import json
import queue
import time
from collections import Counter

import schemas.messages as messages
from common import ros2
from common.drive import CommandGate, RosbotLimits
from common.errors import SchemaError
from common.params import arg_type
from common.ros_link import (
    BridgeLink,
    BridgeTopics,
    RosLink,
    add_ros_args,
    cmd_vel_type,
    open_link,
    ros_domain,
)
from common.transport import Node, open_node, setup_logging
from nodes.base_driver.follow import SPECS as FOLLOW_SPECS
from nodes.base_driver.follow import FollowSettings
from nodes.base_driver.link_drive import LinkDriving, world_pose
from nodes.base_driver.monitor import SPECS as MONITOR_SPECS
from nodes.base_driver.monitor import MonitorSettings
from nodes.base_driver.rosbot import (
    OdomFrame,
    Pose2D,
    cdr_to_robot_odom,
    cdr_to_voltage,
    twist_to_cdr,
    wheel_states,
)
from schemas import Clock, Event, Odometry, Scan, Twist
from worlds import load_world

NAME = "base_driver"
ROS_NODE = "papf_base_driver"    # our ROS 2 node name on rmw_zenoh
ZERO_HOLD_NS = 1_000_000_000     # [ns] zeros keep going out this long after a stop, then silence
ODOM_TIMEOUT_NS = 500_000_000    # [ns] robot odometry older than this is not republished
IDLE_ODOM_HZ = 10.0              # [Hz] odom between runs (teleop's pose line)
EXIT_ZEROS = 3                   # zero commands sent when the node stops
HEALTH_EVERY_NS = 1_000_000_000  # [ns] of run time between `link` reports
APPLIED_EVERY_NS = 200_000_000   # [ns] an unchanged applied command is repeated this often
BatteryVoltage = getattr(messages, "BatteryVoltage", None)   # schemas change requested (issue 5)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``--driver rosbot`` (called by ``nodes.base_driver.__main__``)."""
    g = parser.add_argument_group("rosbot driver (--driver rosbot)")
    d = BridgeTopics()
    g.add_argument("--bridge-namespace", default=d.namespace, metavar="NS",
                   help="zenoh-bridge-ros2dds namespace of the robot's topics (default: none); "
                        "must differ from --namespace")
    g.add_argument("--bridge-cmd-vel", default=d.cmd_vel, metavar="TOPIC", help="(cmd_vel)")
    g.add_argument("--bridge-odom", default=d.odometry, metavar="TOPIC",
                   help="odometry topic (odometry/filtered)")
    g.add_argument("--bridge-battery", default=d.battery, metavar="TOPIC", help="(battery)")
    s = parser.add_argument_group("driving over a slow link (docs/link-driving.md)")
    for name, spec in {**FOLLOW_SPECS, **MONITOR_SPECS}.items():
        default = getattr(FollowSettings() if name in FOLLOW_SPECS else MonitorSettings(), name)
        s.add_argument("--" + name.replace("_", "-"), type=arg_type("--" + name.replace("_", "-"), spec),
                       default=default, metavar="X",
                       help=f"{spec.describe()} (default {default:g}){HELP.get(name, '')}")
    add_ros_args(parser)


HELP = {"max_plan_age": "; the oldest plan the robot drives on while its own scan is fresh",
        "stop_margin": "; the collision monitor's stop zone around the footprint",
        "time_before_collision": "; the monitor slows the robot to keep a return this far ahead",
        "scan_timeout": "; an older scan does not count as the robot's own view"}


def driving_settings(args: argparse.Namespace) -> FollowSettings:
    return FollowSettings(getattr(args, "max_plan_age", FollowSettings.max_plan_age))


def monitor_settings(args: argparse.Namespace) -> MonitorSettings:
    d = MonitorSettings()
    return MonitorSettings(*(getattr(args, n, getattr(d, n)) for n in MONITOR_SPECS))


def bridge_topics(args: argparse.Namespace) -> BridgeTopics:
    d = BridgeTopics()
    topics = BridgeTopics(getattr(args, "bridge_namespace", d.namespace),
                          getattr(args, "bridge_cmd_vel", d.cmd_vel),
                          getattr(args, "bridge_odom", d.odometry),
                          getattr(args, "bridge_battery", d.battery))
    topics.check_separate(args.namespace)
    return topics


class RosbotDriver:
    """Gate our commands to the robot and republish its odometry on the run's clock."""

    def __init__(self, node: Node, topics: BridgeTopics, limits: RosbotLimits, period_ns: int,
                 frame: OdomFrame, link: RosLink | None = None, cmd_type: str = ros2.TWIST,
                 driving: LinkDriving | None = None):
        self.node, self.log, self.topics = node, node.log, topics
        # a stalled loop (a busy computer) never ends in a jump of speed: common/drive.py, rule 5
        self.gate = CommandGate(limits, speed_up_dt_max_s=2 * period_ns * 1e-9)
        self.driving = driving or LinkDriving(limits.watchdog_ns)   # commands during a run
        self.health_due = 0                  # run time [ns] of the next `link` report
        self.applied: tuple[float, float, int] | None = None   # last cmd_vel/applied (v, w, t)
        self.period_ns, self.frame = period_ns, frame
        self.link = link or BridgeLink(node.session, topics.namespace)
        self.cmd_type = cmd_type
        self.cmd_key = self.link.key(topics.cmd_vel, cmd_type)
        self.cmd_pub = self.link.publisher(topics.cmd_vel, cmd_type)
        self.t0: int | None = None          # monotonic ns of run time 0 (None: no run)
        self.tick = 0                       # next tick index of the run
        self.robot = None                   # latest RobotOdom
        self.robot_rx_ns = 0                # monotonic ns it arrived
        self.prev_odom: Odometry | None = None
        self.last_out_ns: int | None = None
        self.zero_since: int | None = None  # monotonic ns the output first was (0, 0)
        self.watchdog_fired = False
        self.odom_lost = False
        self.sent = 0
        self.bad: Counter[str] = Counter()   # undecodable robot messages, per bridge topic
        self.late = 0                        # commands dropped as older than the watchdog
        self.last_run_ns = 0
        self.last_stamp_ns = 0              # [ns] stamp of the last run tick (idle odom's stamp)
        self.idle_ticks = 0

    # -- inputs ---------------------------------------------------------------------------
    def on_command(self, msg: Twist, now: int) -> None:
        if self.t0 is None:                  # between runs (teleop): limits and watchdog only
            self.gate.command(msg.v, msg.w, now)
            self.watchdog_fired = False
            self.send(now)
            return
        rt = self.run_time(now)
        events = self.driving.command(msg, rt, self.pose())
        for kind, detail in events:
            if kind == "command_refused":
                self.late += 1
                if self.driving.should_log():
                    self.log.warning("refused command #%d: %s", self.late, detail)
            self.event(kind, detail, rt)
        if not any(kind == "command_refused" for kind, _ in events):   # obeyed: out at once
            self.send(now)

    def on_scan(self, msg: Scan, now: int) -> None:
        """The robot's own scan: the collision monitor's view (during a run)."""
        if self.t0 is not None:
            self.driving.scan(msg, self.run_time(now), self.pose())

    def pose(self):
        """The robot's latest world pose (x, y, yaw), None without fresh odometry."""
        if self.robot is None or time.monotonic_ns() - self.robot_rx_ns > ODOM_TIMEOUT_NS:
            return None
        odom = self.frame.to_world(self.robot, 0)
        return world_pose(odom.x, odom.y, odom.yaw)

    def on_event(self, msg: Event, now: int) -> None:
        if msg.kind == "run_started":
            self.t0, self.tick, self.prev_odom, self.last_run_ns = now, 0, None, 0
            self.driving.start()
            self.health_due, self.applied = 0, None
            # "frame=keep": a new run after a laptop crash starts where the robot stands, in
            # the world frame it had (papf.launch.resume): no re-anchoring at the world's start
            keep = "frame=keep" in msg.detail.split() and self.frame.anchored
            if self.robot is not None and not keep:
                self.frame.anchor(self.robot.pose)
            self.log.info("run started: clock at 0%s", "" if self.robot else
                          " (no robot odometry yet: waiting for it)")
        elif msg.kind == "run_ended" and self.t0 is not None:
            self.t0 = None
            self.gate.command(0.0, 0.0, now)
            self.log.info("run ended: clock stopped, robot commanded to stop")

    def on_bridge(self, what: str, data: bytes, now: int) -> None:
        try:
            if what == "odometry":
                self.robot, self.robot_rx_ns = cdr_to_robot_odom(data), now
                if self.t0 is not None and not self.frame.anchored:
                    self.frame.anchor(self.robot.pose)
            else:
                self.publish_voltage(cdr_to_voltage(data))
        except SchemaError as exc:
            self.bad[what] += 1
            if self.bad[what] <= 5 or self.bad[what] % 100 == 0:
                self.log.warning("dropped bad robot message #%d on %s: %s", self.bad[what],
                                 getattr(self.topics, what), exc)

    # -- outputs --------------------------------------------------------------------------
    def run_time(self, now: int) -> int:
        """Run time [ns] at monotonic ``now`` (the last run's end time between runs)."""
        if self.t0 is not None:
            self.last_run_ns = now - self.t0
        return self.last_run_ns

    def send(self, now: int) -> None:
        """Put the gated command on the bridge (silence once stopped for ZERO_HOLD)."""
        if self.t0 is not None and self.driving.follower.cmd is not None:
            self.follow(now)
        if self.gate.last_command_ns is None:
            return                               # never commanded: leave the robot alone
        dt = 0.0 if self.last_out_ns is None else (now - self.last_out_ns) * 1e-9
        self.last_out_ns = now
        v, w, stopped = self.gate.output(now, dt)
        if stopped and not self.watchdog_fired:
            self.watchdog_fired = True
            age = (now - self.gate.last_command_ns) * 1e-9
            self.log.warning("watchdog: no command for %.3f s: stopping the robot", age)
            self.event("watchdog_stop", f"no cmd_vel for {age:.3f} s (limit "
                       f"{self.gate.limits.watchdog_ns * 1e-9:g} s); commanding zero velocity")
        self.applied_out(v, w, now)
        if v == 0.0 and w == 0.0:
            self.zero_since = self.zero_since or now
            if now - self.zero_since > ZERO_HOLD_NS:
                return
        else:
            self.zero_since = None
        self.cmd_pub.put(twist_to_cdr(v, w, self.cmd_type, time.time_ns()))
        self.sent += 1

    def follow(self, now: int) -> None:
        """During a run: the follower's target (plan, collision monitor) becomes the gate's."""
        rt = self.run_time(now)
        v, w, events = self.driving.control(rt, self.pose())
        for kind, detail in events:
            if kind == "watchdog_stop":
                self.watchdog_fired = True
                self.log.warning("watchdog: %s", self.driving.stopped_why)
            self.event(kind, detail, rt)
        if self.driving.stopped_why is None:
            self.watchdog_fired = False
        self.gate.command(v, w, now)

    def applied_out(self, v: float, w: float, now: int) -> None:
        """``cmd_vel/applied`` during a run: on a change, else every APPLIED_EVERY_NS."""
        if self.t0 is None:
            return
        rt = self.run_time(now)
        last = self.applied
        if last is not None and (last[0], last[1]) == (v, w) and rt - last[2] < APPLIED_EVERY_NS:
            return
        self.applied = (v, w, rt)
        self.node.publish("cmd_vel/applied", Twist(stamp_ns=rt, v=v, w=w))

    def on_tick(self, now: int) -> None:
        self.send(now)
        fresh = self.robot is not None and now - self.robot_rx_ns <= ODOM_TIMEOUT_NS
        if self.t0 is None:
            self.idle_odom(now, fresh)
            return
        stamp = self.last_stamp_ns = self.tick * self.period_ns
        if self.run_time(now) >= self.health_due:
            self.health_due = self.run_time(now) + HEALTH_EVERY_NS
            self.node.publish("link", self.driving.health(self.run_time(now)))
        if fresh:
            odom = self.frame.to_world(self.robot, stamp)
            self.node.publish("odom", odom)
            self.node.publish("wheels", wheel_states(self.prev_odom, odom))
            self.prev_odom = odom
            if self.odom_lost:
                self.odom_lost = False
                self.log.info("robot odometry back")
        elif not self.odom_lost and (self.robot is not None or stamp > ODOM_TIMEOUT_NS):
            self.odom_lost = True
            self.event("node_fault", f"no robot odometry on {self.topics.odometry} "
                       f"for > {ODOM_TIMEOUT_NS * 1e-9:g} s: odom not published")
        self.node.publish("clock", Clock(stamp_ns=stamp))

    def idle_odom(self, now: int, fresh: bool) -> None:
        """Between runs: fresh robot odometry every 1/IDLE_ODOM_HZ, no wheels, no clock."""
        every = max(1, round(1e9 / IDLE_ODOM_HZ / self.period_ns))
        self.idle_ticks += 1
        if fresh and self.idle_ticks % every == 0:
            if self.last_stamp_ns:   # after a run: its clock goes on (a stamp is never repeated)
                self.last_stamp_ns += every * self.period_ns
            self.node.publish("odom", self.frame.to_world(self.robot, self.last_stamp_ns))

    def next_tick_at(self, now: int) -> int:
        """Monotonic ns of the next tick (run ticks on the run's grid; skipped ones dropped)."""
        if self.t0 is None:
            return now + self.period_ns
        behind = (now - self.t0) // self.period_ns
        self.tick = max(self.tick, behind)
        return self.t0 + self.tick * self.period_ns

    def event(self, kind: str, detail: str, stamp_ns: int | None = None) -> None:
        stamp = self.run_time(time.monotonic_ns()) if stamp_ns is None else stamp_ns
        self.node.publish("events", Event(stamp_ns=stamp, kind=kind, source=NAME, detail=detail))

    def publish_voltage(self, voltage: float) -> None:
        stamp = self.run_time(time.monotonic_ns())
        if BatteryVoltage is not None:
            self.node.publish("battery/measured", BatteryVoltage(stamp_ns=stamp, voltage=voltage))
        else:
            self.node.publish("events", Event(stamp_ns=stamp, kind="info", source=NAME,
                                              detail=f"battery_voltage_V={voltage:.3f}"))

    def run_state(self, query) -> None:
        """Answer ``<ns>/run/state`` (Zenoh's thread): the run this driver is in, sealed
        (:func:`papf.launch.resume.robot_run` reads it: a laptop that comes back)."""
        now = time.monotonic_ns()
        pose = None
        if self.robot is not None:
            odom = self.frame.to_world(self.robot, 0)
            pose = (odom.x, odom.y)
        running = self.t0 is not None
        t_ns = now - self.t0 if running else self.last_run_ns
        x, y = pose if pose is not None else (None, None)
        payload = json.dumps({"run": self.node.trust.run_hex() if running else "",
                              "running": running, "t_ns": t_ns, "x": x, "y": y}).encode()
        key = str(query.key_expr)
        att = self.node.trust.seal(self.node.keys.key("run/state"), payload)
        try:
            if att is None:
                query.reply(key, payload)
            else:
                query.reply(key, payload, attachment=att)
        except Exception as exc:   # a closing session
            self.log.debug("run state not answered: %s", exc)

    def stop_robot(self) -> None:
        """Before the node exits: a moving robot is brought to a stop at its limits (the gate's
        ramp, a tick at a time, at most the time a stop at the limits takes), then
        :data:`EXIT_ZEROS` zero commands go out. A zero straight away would be a step of speed
        the robot's limits forbid (seen: 0.27 m/s to 0 when a split run's robot side was stopped
        while it braked after the run's end); a process killed outright is stopped by the
        robot's own ``cmd_vel_timeout``."""
        self.t0 = None   # no run any more: the follower no longer steers the gate
        self.watchdog_fired = True   # stopping already: the ramp is not a lost command
        if self.gate.last_command_ns is not None:
            now = time.monotonic_ns()
            self.gate.command(0.0, 0.0, max(now, self.gate.last_command_ns))
            end = now + int(self.gate.stop_time_s() * 1e9) + 2 * self.period_ns
            while self.gate.last_output != (0.0, 0.0) and now < end:
                time.sleep(self.period_ns * 1e-9)
                now = time.monotonic_ns()
                self.send(now)
        for _ in range(EXIT_ZEROS):
            self.cmd_pub.put(twist_to_cdr(0.0, 0.0, self.cmd_type, time.time_ns()))

    # -- loop -----------------------------------------------------------------------------
    def watchdog_due(self) -> int | None:
        """Monotonic ns at which the watchdog fires (so a stop goes out on time, not a tick late)."""
        last = self.gate.last_command_ns
        if last is None or self.watchdog_fired:
            return None
        return last + self.gate.limits.watchdog_ns + 1

    def run(self) -> None:
        node, inbox = self.node, self.node.inbox
        due = self.next_tick_at(time.monotonic_ns())
        while not node.stop:
            now = time.monotonic_ns()
            if now >= due:
                self.on_tick(now)
                if self.t0 is not None:
                    self.tick += 1
                due = self.next_tick_at(now) if self.t0 is not None else now + self.period_ns
                continue
            wd = self.watchdog_due()
            if wd is not None and now >= wd:
                self.send(now)
                continue
            wake = due if wd is None else min(due, wd)
            try:
                topic, msg = inbox.get(timeout=(wake - now) * 1e-9)
            except queue.Empty:
                continue
            now = time.monotonic_ns()
            if topic is None:         # the stop request's wake-up (node.stop): not a message
                continue
            if topic == "cmd_vel":
                self.on_command(msg, now)
            elif topic == "scan":
                self.on_scan(msg, now)
            elif topic == "events":
                self.on_event(msg, now)
                due = min(due, self.next_tick_at(now))
            else:
                self.on_bridge(topic, msg, now)


def main(args: argparse.Namespace) -> int:
    log = setup_logging(NAME, getattr(args, "log_level", "INFO"))
    topics = bridge_topics(args)
    cmd_type = cmd_vel_type(args)
    limits = RosbotLimits(watchdog_ns=int(round(getattr(args, "watchdog", 0.5) * 1e9)))
    period_ns = int(round(1e9 / getattr(args, "odom_hz", 50.0)))
    world = getattr(args, "world", None)
    start = Pose2D(*load_world(world).start) if world else Pose2D(0.0, 0.0, 0.0)
    ros_domain(args)                       # a bad domain: exit 2 before any session opens
    with open_node(NAME, args, log) as node:
        node.subscribe("cmd_vel")
        node.subscribe("events")
        node.subscribe("scan")     # the robot's own LiDAR: the collision monitor's view
        link = open_link(args, node.session, ROS_NODE, topics.namespace)
        for what, typename in (("odometry", ros2.ODOMETRY), ("battery", ros2.BATTERY_STATE)):
            link.subscribe(getattr(topics, what), typename,
                           lambda data, w=what: node.inbox.put((w, data)))
        node.declare_publishers("odom", "wheels", "clock", "events", "link", "cmd_vel/applied")
        driving = LinkDriving(limits.watchdog_ns, driving_settings(args), monitor_settings(args))
        driver = RosbotDriver(node, topics, limits, period_ns, OdomFrame(start), link, cmd_type,
                              driving)
        log.info("rosbot driver over %s: cmd_vel %s (%s), odometry %s; limits %s",
                 link.middleware, driver.cmd_key, cmd_type,
                 link.key(topics.odometry, ros2.ODOMETRY), limits)
        state_q = node.session.declare_queryable(node.keys.key("run/state"), driver.run_state)
        node.ready()
        try:
            driver.run()
        finally:
            driver.stop_robot()
            state_q.undeclare()
            link.close()
            refused = node.trust.counts().get("cmd_vel", {})
            log.info("stopped: %d commands sent to the robot, %d late ones dropped, %d refused "
                     "(not this run's planner: %s)", driver.sent, driver.late,
                     sum(refused.values()), refused or "none")
    return 0
