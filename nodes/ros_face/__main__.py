"""ROS 2 face node: the stack as ROS 2 nodes and topics on rmw_zenoh (RViz, ``ros2 topic``).

    python -m nodes.ros_face [--ros-domain N] [--ros-namespace NS] [--goals accept|refuse]

Subscribes our keys (ports below) and publishes, on rmw_zenoh's wire format
(:mod:`common.ros_link`), ``/scan``, ``/odom``, ``/tf``, ``/tf_static`` and
``/robot_description`` (transient local), ``/cmd_vel``, ``/battery``, ``/plan`` and
``/markers``, each from the ROS 2 node ``/papf_<stack node>`` it stands for; it takes
``/goal_pose`` (RViz's "2D Goal Pose", frame ``odom``) and publishes it as our goal with
``--goals accept`` (signed with the run's key, as ``papf goal``), or drops it with a log
line with ``--goals refuse`` (lockstep runs stay deterministic). ``docs/ros2-face.rviz``
shows all of it. With ``--ros-namespace r1`` the topics are ``/r1/scan``, ….

Safety: the face's ``/cmd_vel`` is what the planner asks, not what the base driver lets
through; on a domain where something that is not ours subscribes ``/cmd_vel`` (a robot's
controller) the face would drive it around the driver's limits and watchdog, so it
refuses to start there (exit 2): give the face a domain of its own.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from collections import Counter

from common import rmw_zenoh as rz
from common import runauth
from common.cliparse import ArgumentParser
from common.errors import ConfigError, PapfError, SchemaError
from common.ports import describe
from common.ros_link import RmwZenohLink, ros_domain
from common.transport import Node, add_zenoh_args, exit_fast, open_node, setup_logging
from nodes.ros_face.core import FACE_TOPICS, GOAL_TOPIC, SUBSCRIBED, FaceCore
from nodes.ros_face.ports import PORTS, VARIANTS

NAME = "ros_face"
GOAL_IN = "ros_goal_pose"            # inbox tag of /goal_pose samples
GUARDED = "cmd_vel"                  # a foreign subscriber of this face topic: refuse


def parse_args(argv=None) -> argparse.Namespace:
    """The face's command line: ROS domain, namespace and the bus options."""
    ap = ArgumentParser(prog="python -m nodes.ros_face", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=describe(PORTS, VARIANTS))
    ap.add_argument("--ros-domain", type=int, default=None, metavar="N",
                    help="ROS domain of the face (default: $ROS_DOMAIN_ID, else 0)")
    ap.add_argument("--ros-namespace", default="", metavar="NS",
                    help="ROS namespace of the face's topics (default: none: /scan, /odom …)")
    ap.add_argument("--goals", choices=("accept", "refuse"), default="accept",
                    help="/goal_pose: set it as the goal (default) or refuse it with a log line")
    ap.add_argument("--log-level", default="INFO")
    add_zenoh_args(ap)
    return ap.parse_args(argv)


def foreign_subscribers(session, domain: int, topic: str, timeout_s: float = 1.0) -> list[str]:
    """ROS 2 nodes (not ``papf_*``) whose liveliness tokens say they subscribe ``topic``."""
    found = []
    for reply in session.liveliness().get(rz.liveliness_subscription(domain), timeout=timeout_s):
        if reply.ok is None:
            continue
        try:
            e = rz.Entity.parse(str(reply.ok.key_expr))
        except SchemaError:
            continue
        if e.kind == rz.SUBSCRIPTION and e.topic == topic and not e.node.startswith("papf_"):
            found.append(e.fq_node)
    return sorted(set(found))


class Face:
    """Our keys in, the face's ROS 2 publishers out; /goal_pose to our goal."""

    def __init__(self, node: Node, domain: int, namespace: str, accept_goals: bool):
        self.node, self.log, self.accept_goals = node, node.log, accept_goals
        self.core = FaceCore()
        self.key = runauth.key_from_env()
        ids = itertools.count(0)
        links = {}
        for spec in (*FACE_TOPICS.values(), GOAL_TOPIC):
            if spec.node not in links:
                links[spec.node] = RmwZenohLink(node.session, domain, f"papf_{spec.node}",
                                                namespace, ids)
        self.links = list(links.values())
        self.pubs = {t: links[s.node].publisher(t, s.typename, s.qos) for t, s in FACE_TOPICS.items()}
        links[GOAL_TOPIC.node].subscribe("goal_pose", GOAL_TOPIC.typename,
                                         lambda data: node.inbox.put((GOAL_IN, data)), GOAL_TOPIC.qos)
        self.sent: Counter[str] = Counter()
        self.bad_goals = 0

    def publish(self, outputs) -> None:
        """Put each (ROS topic, CDR bytes) of ``outputs`` on its publisher and count it."""
        for topic, data in outputs:
            self.pubs[topic].put(data)
            self.sent[topic] += 1

    def on_goal_pose(self, data: bytes) -> None:
        """A ``/goal_pose`` from ROS -> our goal; a malformed one is logged and dropped."""
        try:
            goal = self.core.goal_from_pose(data)
        except SchemaError as exc:
            self.bad_goals += 1
            self.log.warning("dropped /goal_pose #%d: %s", self.bad_goals, exc)
            return
        if not self.accept_goals:
            self.log.warning("/goal_pose (%.2f, %.2f) refused: this lockstep run keeps its "
                             "world's goal (runs stay deterministic); use papf launch", goal.x, goal.y)
            return
        self.node.publish("goal", runauth.sign(goal, self.key))
        self.log.info("goal set from /goal_pose: (%.2f, %.2f)", goal.x, goal.y)

    def run(self) -> None:
        """Publish the static messages, then translate every message until the node stops."""
        self.publish(self.core.static())
        for topic, msg in self.node.messages(tick_s=0.1):
            if topic == GOAL_IN:
                self.on_goal_pose(msg)
            elif topic is not None:
                self.publish(self.core.on_message(topic, msg))

    def close(self) -> None:
        """Undeclare the ROS links' publishers and subscribers."""
        for link in self.links:
            link.close()


def serve(args: argparse.Namespace, log) -> int:
    """Run the face; ConfigError if another ROS node subscribes the guarded topic."""
    domain = ros_domain(args)
    with open_node(NAME, args, log) as node:
        others = foreign_subscribers(node.session, domain, rz.topic_name(GUARDED, args.ros_namespace))
        if others:
            raise ConfigError(f"ROS domain {domain}: {', '.join(others)} subscribe "
                              f"{rz.topic_name(GUARDED, args.ros_namespace)}; the face's commands "
                              "would drive the robot around the base driver's limits: give the face "
                              "its own domain (--ros-face-domain / --ros-domain)")
        for topic in SUBSCRIBED:
            node.subscribe(topic)
        node.declare_publishers("goal")
        face = Face(node, domain, args.ros_namespace, args.goals == "accept")
        node.ready()
        log.info("ROS 2 face on rmw_zenoh, domain %d: %s", domain,
                 ", ".join(rz.topic_name(t, args.ros_namespace) for t in FACE_TOPICS))
        started = time.monotonic()
        try:
            face.run()
        finally:
            face.close()
            log.info("stopped after %.0f s: published %s; %d bad /goal_pose dropped",
                     time.monotonic() - started, dict(face.sent), face.bad_goals)
    return 0


def main(argv=None) -> int:
    """``python -m nodes.ros_face``: run the face; the exit code (2 on a bad setting)."""
    args = parse_args(argv)
    log = setup_logging(NAME, args.log_level)
    try:
        return serve(args, log)
    except PapfError as exc:
        print(f"ros_face: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    exit_fast(main())
