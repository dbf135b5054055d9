"""ROS 2 face node: the stack as ROS 2 nodes, topics, parameters and Nav2's action on rmw_zenoh.

    python -m nodes.ros_face [--ros-domain N] [--ros-namespace NS] [--ros-distro jazzy|humble]
                             [--goals accept|refuse] [--world W]

Subscribes our keys (ports below) and publishes, on rmw_zenoh's wire format
(:mod:`common.ros_link`), ``/scan`` (sensor-data QoS: best effort), ``/odom``, ``/tf``
(odom -> base_link, the wheels, map -> odom with a map), ``/tf_static`` and
``/robot_description`` (transient local), ``/joint_states``, ``/clock`` (sim time),
``/map`` (transient local, with ``--world``), ``/cmd_vel``, ``/battery`` (1 Hz), ``/plan``,
``/markers`` and ``/diagnostics`` (1 Hz), each from the ROS 2 node ``/papf_<stack node>`` it
stands for. ``/papf_planner`` also serves the ROS 2 parameter services
(:mod:`nodes.ros_face.params`: ``ros2 param list /papf_planner``) and Nav2's
``navigate_to_pose`` action (:mod:`nodes.ros_face.navigate`), and takes ``/goal_pose``
(RViz's "2D Goal Pose"). With ``--goals accept`` goals, actions and parameter sets from
ROS 2 go to the stack (signed with the run's key, as ``papf goal`` / ``papf param``; every
parameter still passes the planner's range and safety checks); with ``--goals refuse``
(lockstep runs: deterministic) they are refused and parameters are read-only. With
``--ros-namespace r1`` the names are ``/r1/scan``, ….

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

from common import param_query, runauth
from common import rmw_zenoh as rz
from common import ros2_convert as rc
from common import ros2_interfaces as ri
from common.cliparse import ArgumentParser
from common.errors import ConfigError, PapfError, SchemaError
from common.ports import describe
from common.ros_link import RmwZenohLink, add_distro_arg, ros_distro, ros_domain
from common.transport import Node, add_zenoh_args, exit_fast, open_node, setup_logging
from nodes.ros_face.core import FACE_TOPICS, GOAL_TOPIC, SUBSCRIBED, FaceCore
from nodes.ros_face.navigate import ACTION, Navigator
from nodes.ros_face.params import ParamServer
from nodes.ros_face.ports import PORTS, VARIANTS
from worlds.map_world import world_map

NAME = "ros_face"
GOAL_IN = "ros_goal_pose"            # inbox tag of /goal_pose samples
SERVICE_IN = "ros_service"           # inbox tag of service requests
GUARDED = "cmd_vel"                  # a foreign subscriber of this face topic: refuse
ACTION_NAME = "navigate_to_pose"     # Nav2's bt_navigator serves it under this name
ACTION_SERVICES = {"send_goal": f"{ACTION}_SendGoal", "cancel_goal": ri.CANCEL_GOAL,
                   "get_result": f"{ACTION}_GetResult"}
STATUS_QOS = rz.Qos(durability=1, depth=1)      # rcl_action_qos_profile_status_default
PARAMS_QOS = rz.Qos(depth=1000)                 # rmw_qos_profile_parameters
EVENTS_QOS = rz.Qos(depth=1000)                 # rmw_qos_profile_parameter_events
STACK_NODES = ("base_driver", "lidar_sim", "planner", "energy_meter")
ANSWER_S = 3.0                                  # [s] for the planner to answer a params query
DIAGNOSTICS_S = 1.0                             # [s wall] between /diagnostics


def parse_args(argv=None) -> argparse.Namespace:
    """The face's command line: ROS domain, namespace, distro and the bus options."""
    ap = ArgumentParser(prog="python -m nodes.ros_face", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=describe(PORTS, VARIANTS))
    ap.add_argument("--ros-domain", type=int, default=None, metavar="N",
                    help="ROS domain of the face (default: $ROS_DOMAIN_ID, else 0)")
    ap.add_argument("--ros-namespace", default="", metavar="NS",
                    help="ROS namespace of the face's topics (default: none: /scan, /odom …)")
    add_distro_arg(ap)
    ap.add_argument("--goals", choices=("accept", "refuse"), default="accept",
                    help="goals (/goal_pose, navigate_to_pose) and parameter sets from ROS 2: "
                         "take them (default) or refuse them (parameters read-only)")
    ap.add_argument("--world", metavar="W",
                    help="the run's world: /map (its map, or its obstacles rasterised) and map -> odom")
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
    """Our keys in, the face's ROS 2 publishers, services and action out."""

    def __init__(self, node: Node, args: argparse.Namespace, domain: int, grid):
        self.node, self.log = node, node.log
        self.accept_goals = args.goals == "accept"
        self.distro = ros_distro(args)
        self.core = FaceCore(grid)
        self.key = runauth.key_from_env()
        self.links = self._links(node, domain, args.ros_namespace)
        self.pubs = {t: self.links[s.node].publisher(t, s.typename, s.qos)
                     for t, s in FACE_TOPICS.items() if t != "map" or grid is not None}
        planner = self.links["planner"]
        planner.subscribe("goal_pose", GOAL_TOPIC.typename,
                          lambda data: node.inbox.put((GOAL_IN, data)), GOAL_TOPIC.qos)
        self.params = ParamServer(self._ask, self.accept_goals, self.distro)
        self.navigator = Navigator(self.distro, self.accept_goals, self.log)
        self._serve(planner)
        self.sent: Counter[str] = Counter()
        self.dropped: Counter[str] = Counter()
        self.alive: set[str] = set()
        self.gone: set[str] = set()
        self._alive_sub = node.session.liveliness().declare_subscriber(
            node.keys.key("alive/*"), self._on_alive, history=True)
        self.next_diag = 0.0

    def _links(self, node: Node, domain: int, namespace: str) -> dict[str, RmwZenohLink]:
        ids, links = itertools.count(0), {}
        for spec in (*FACE_TOPICS.values(), GOAL_TOPIC):
            if spec.node not in links:
                links[spec.node] = RmwZenohLink(node.session, domain, f"papf_{spec.node}",
                                                namespace, ids, self.distro, self.log)
        return links

    def _serve(self, planner: RmwZenohLink) -> None:
        """The planner's parameter services, Nav2's action, /parameter_events."""
        node_name = planner.node_entity.node

        def queue(name):
            return lambda data, reply: self.node.inbox.put((SERVICE_IN, (name, data, reply)))

        for service, typename in ri.PARAM_SERVICES.items():
            planner.service(f"{node_name}/{service}", typename, queue(service), PARAMS_QOS)
        for service, typename in ACTION_SERVICES.items():
            planner.service(f"{ACTION_NAME}/_action/{service}", typename, queue(service))
        self.feedback = planner.publisher(f"{ACTION_NAME}/_action/feedback",
                                          f"{ACTION}_FeedbackMessage", rz.RELIABLE_10)
        self.status = planner.publisher(f"{ACTION_NAME}/_action/status",
                                        "action_msgs/msg/GoalStatusArray", STATUS_QOS)
        self.param_events = planner.publisher("parameter_events",
                                              "rcl_interfaces/msg/ParameterEvent", EVENTS_QOS)
        self.planner_fq = planner.node_entity.fq_node

    # -- our side ---------------------------------------------------------------------------------
    def _ask(self, request: dict, signed: bool) -> dict:
        """Our planner's reply to a params request (signed with the run's key when ``signed``)."""
        if signed:
            request = runauth.sign_request(request, self.key)
        key = self.node.keys.key("planner/params")
        out = param_query.ask(self.node.session, key, request, ANSWER_S)
        if out is None:
            raise ConfigError(f"the planner did not answer on {key} within {ANSWER_S:g} s")
        return out

    def _on_alive(self, sample) -> None:
        name = str(sample.key_expr).rsplit("/", 1)[-1]
        if str(sample.kind).endswith("DELETE"):
            self.alive.discard(name)
            self.gone.add(name)
        else:
            self.alive.add(name)
            self.gone.discard(name)

    def publish(self, outputs) -> None:
        """Put each (ROS topic, CDR bytes) of ``outputs`` on its publisher and count it."""
        for topic, data in outputs:
            self.pubs[topic].put(data)
            self.sent[topic] += 1

    # -- requests from ROS 2 -------------------------------------------------------------------
    def on_goal_pose(self, data: bytes) -> None:
        """A ``/goal_pose`` from ROS -> our goal; a malformed one is logged and dropped."""
        try:
            goal = self.core.goal_from_pose(data)
        except SchemaError as exc:
            self._drop("goal_pose", exc)
            return
        if not self.accept_goals:
            self.log.warning("/goal_pose (%.2f, %.2f) refused: this lockstep run keeps its "
                             "world's goal (runs stay deterministic); use papf launch", goal.x, goal.y)
            return
        self.node.publish("goal", runauth.sign(goal, self.key))
        self.log.info("goal set from /goal_pose: (%.2f, %.2f)", goal.x, goal.y)

    def on_service(self, name: str, data: bytes, reply) -> None:
        """One service request (parameters or the action); garbage is counted and dropped."""
        try:
            if name in ri.PARAM_SERVICES:
                self._on_params(name, data, reply)
            else:
                self._on_action(name, data, reply)
        except (SchemaError, ConfigError) as exc:
            self._drop(name, exc)

    def _on_params(self, name: str, data: bytes, reply) -> None:
        response, changed = self.params.handle(name, data)
        reply.send(response)
        if changed:
            self.log.info("parameters set from ROS 2: %s", ", ".join(changed))
            self.param_events.put(self.params.event(changed, self.planner_fq, time.time_ns()))

    def _on_action(self, name: str, data: bytes, reply) -> None:
        nav = self.navigator
        if name == "send_goal":
            response, goal, replies = nav.send_goal(data)
            reply.send(response)
            if goal is not None:
                self.node.publish("goal", runauth.sign(goal, self.key))
            self.status.put(nav.status_array())
            self._answer(replies)
            return
        elif name == "cancel_goal":
            response, stop = nav.cancel_goal(data)
            reply.send(response)
            if stop is not None:
                self.node.publish("goal", runauth.sign(stop, self.key))
        else:
            self._answer(nav.get_result(data, reply))
            return
        self.status.put(nav.status_array())

    def _answer(self, replies) -> None:
        for reply, cdr in replies:
            reply.send(cdr)

    def _drop(self, what: str, exc: Exception) -> None:
        self.dropped[what] += 1
        if self.dropped[what] <= 5:
            self.log.warning("dropped %s request #%d: %s", what, self.dropped[what], exc)

    # -- our messages ------------------------------------------------------------------------------
    def on_message(self, topic: str, msg) -> None:
        """One of our messages: the face's topics, and what the action makes of it."""
        self.publish(self.core.on_message(topic, msg))
        nav = self.navigator
        if topic == "odom":
            fb = nav.on_odom(msg)
            if fb is not None:
                self.feedback.put(fb)
        elif topic == "planner/status":
            before = [e.status for e in nav.goals.values()]
            replies = nav.on_status(msg)
            if [e.status for e in nav.goals.values()] != before:   # the status first, as rclcpp
                self.status.put(nav.status_array())
            self._answer(replies)
        elif topic == "planner/state":
            nav.on_state(msg)
        elif topic == "goal":
            nav.on_goal(msg)

    def diagnostics(self, now: float) -> None:
        """``/diagnostics`` once a second: each stack node alive or gone, the face's counts."""
        if now < self.next_diag:
            return
        self.next_diag = now + DIAGNOSTICS_S
        rows = [(f"papf: {n}", 0 if n in self.alive else 2, "alive" if n in self.alive else
                 ("gone" if n in self.gone else "not seen"), {}) for n in STACK_NODES]
        rows.append(("papf: ros_face", 1 if self.dropped else 0,
                     f"{sum(self.dropped.values())} bad requests dropped" if self.dropped else "ok",
                     {**{f"published {t}": n for t, n in sorted(self.sent.items())},
                      **{f"dropped {t}": n for t, n in sorted(self.dropped.items())}}))
        self.publish([("diagnostics", rc.serialize(rc.diagnostics(time.time_ns(), rows),
                                                   rc.DIAGNOSTIC_ARRAY))])

    def run(self) -> None:
        """Publish the static messages, then translate every message until the node stops."""
        self.publish(self.core.static())
        self.status.put(self.navigator.status_array())
        for topic, msg in self.node.messages(tick_s=0.1):
            if topic == GOAL_IN:
                self.on_goal_pose(msg)
            elif topic == SERVICE_IN:
                self.on_service(*msg)
            elif topic is not None:
                self.on_message(topic, msg)
            self.diagnostics(time.monotonic())

    def close(self) -> None:
        """Undeclare the ROS links' publishers, services and subscribers."""
        self._alive_sub.undeclare()
        for link in self.links.values():
            link.close()


def serve(args: argparse.Namespace, log) -> int:
    """Run the face; ConfigError if another ROS node subscribes the guarded topic."""
    domain = ros_domain(args)
    ros_distro(args)
    grid = world_map(args.world)
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
        face = Face(node, args, domain, grid)
        node.ready()
        log.info("ROS 2 face on rmw_zenoh (%s), domain %d: %s; action /%s; parameters of %s",
                 face.distro, domain, ", ".join(rz.topic_name(t, args.ros_namespace)
                                                for t in face.pubs), ACTION_NAME, face.planner_fq)
        started = time.monotonic()
        try:
            face.run()
        finally:
            face.close()
            log.info("stopped after %.0f s: published %s; dropped %s",
                     time.monotonic() - started, dict(face.sent), dict(face.dropped))
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
