"""Viewer node: a namespace's Zenoh traffic as a Foxglove WebSocket server.

    python -m nodes.viewer [--host 127.0.0.1] [--port 8765] [--world W] [--goals accept|refuse]

Open ``ws://HOST:PORT`` in Foxglove (Open connection -> Foxglove WebSocket) and load
``docs/foxglove-layout.json``. Ports: :mod:`nodes.viewer.ports` (``--help`` prints them);
besides them it queries ``<ns>/planner/params`` (the Parameters panel) and serves the
channels of ``core.CHANNELS`` on ``ws://HOST:PORT``. A pose/point published from the 3D
panel is published on ``<ns>/goal`` with ``--goals accept``, refused with a log line with
``--goals refuse``.

Exit code 2 on a bad setting (unknown world, port taken).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import sys
import time

import foxglove
import zenoh
from foxglove.websocket import Capability, Parameter, ParameterType

from common import runauth
from common.cliparse import ArgumentParser
from common.errors import ConfigError, PapfError
from common.params import PORT, arg_type
from common.ports import describe
from common.transport import Node, add_zenoh_args, open_node, setup_logging
from nodes.viewer.convert import LOG_INFO, LOG_WARNING
from nodes.viewer.core import GOAL_TOPICS, SUBSCRIBED, ViewCore, goal_from_client, param_sets
from nodes.viewer.ports import PORTS, VARIANTS
from nodes.viewer.sink import FoxgloveChannels
from schemas.messages import Goal
from worlds import load_world

NAME = "viewer"
STATIC_EVERY_S = 1.0     # [s wall] world and goal re-sent for clients that join late
PARAMS_TIMEOUT_S = 2.0   # [s] for the planner to answer a parameter query
CLIENT = "__client__"    # inbox topic of what a Foxglove client published


class Listener(foxglove.websocket.ServerListener):
    """Foxglove client -> stack: goals go to the node's inbox, parameters to the planner."""

    def __init__(self, node: Node, log: logging.Logger, accept_params: bool = True):
        self.node, self.log, self.accept_params = node, log, accept_params
        self.client_topics: dict[tuple[int, int], str] = {}

    def on_client_advertise(self, client, channel) -> None:
        """Foxglove client advertised ``channel``: remember its topic."""
        self.client_topics[(client.id, channel.id)] = channel.topic

    def on_client_unadvertise(self, client, client_channel_id: int) -> None:
        """Foxglove client withdrew a channel: forget its topic."""
        self.client_topics.pop((client.id, client_channel_id), None)

    def on_message_data(self, client, client_channel_id: int, data: bytes) -> None:
        """A message from a Foxglove client (a goal, a click) -> the node's inbox."""
        topic = self.client_topics.get((client.id, client_channel_id), "")
        self.node.inbox.put((CLIENT, (topic, bytes(data))))

    # -- parameters (answered on the SDK's thread: a blocking Zenoh query) --
    def _query(self, request: dict) -> dict | None:
        key = self.node.keys.key("planner/params")
        if request.get("set"):
            if not self.accept_params:
                return {"params": {}, "error": "this viewer was started with --params refuse "
                        "(papf run keeps its settings: runs stay comparable); use papf launch"}
            request = runauth.sign_request(request, runauth.key_from_env())
        payload = json.dumps(request).encode()
        for reply in self.node.session.get(key, payload=payload, timeout=PARAMS_TIMEOUT_S):
            if reply.ok is not None:
                return json.loads(reply.ok.payload.to_bytes())
        return None

    def _params(self, reply: dict | None, names=None) -> list[Parameter]:
        if reply is None:
            return []
        return [_parameter(k, v) for k, v in reply["params"].items() if not names or k in names]

    def on_get_parameters(self, client, param_names: list[str], request_id=None):
        """Foxglove asks parameters: the planner's, those of ``param_names`` (all if empty)."""
        return self._params(self._query({}), param_names)

    def on_set_parameters(self, client, parameters: list[Parameter], request_id=None):
        """Foxglove sets parameters: sent to the planner; its answer goes to the log."""
        sets = param_sets({p.name: p.get_value() for p in parameters})
        reply = self._query({"set": sets})
        if reply is None:
            self.node.inbox.put((CLIENT, ("/params/refused",
                                          f"{sets}: the planner did not answer".encode())))
        elif reply["error"]:
            self.node.inbox.put((CLIENT, ("/params/refused", reply["error"].encode())))
        else:
            self.node.inbox.put((CLIENT, ("/params/set", ", ".join(sets).encode())))
        return self._params(reply, [p.name for p in parameters])


def _parameter(name: str, value) -> Parameter:
    if isinstance(value, float):
        return Parameter(name, value=value, type=ParameterType.Float64)
    return Parameter(name, value=value)


def parse_args(argv=None) -> argparse.Namespace:
    """The viewer's command line: world, WebSocket host and port, bus options."""
    ap = ArgumentParser(prog="python -m nodes.viewer", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=describe(PORTS, VARIANTS))
    add_view_args(ap)
    ap.add_argument("--log-level", default="INFO")
    add_zenoh_args(ap)
    return ap.parse_args(argv)


def add_view_args(ap: argparse.ArgumentParser) -> None:
    """The viewer's own options (shared with ``papf view``)."""
    ap.add_argument("--host", default="127.0.0.1", help="WebSocket address (default 127.0.0.1)")
    ap.add_argument("--port", type=arg_type("--port", PORT), default=8765,
                    help="WebSocket port (default 8765)")
    ap.add_argument("--world", help="world to draw (packaged name or .toml path)")
    ap.add_argument("--params", choices=("accept", "refuse"), default="accept",
                    help="parameter changes from Foxglove: pass them to the planner, signed with "
                         "the launcher's run key (default), or refuse them")
    ap.add_argument("--goals", choices=("accept", "refuse"), default="accept",
                    help="goals published from Foxglove: set them (default) or refuse them "
                         "with a log line (lockstep runs stay deterministic)")


class Viewer:
    """The node's main-thread side: core in, SDK channels out, client goals handled."""

    def __init__(self, node: Node, core: ViewCore, channels: FoxgloveChannels, accept_goals: bool):
        self.node, self.core, self.channels = node, core, channels
        self.accept_goals = accept_goals
        self.key = runauth.key_from_env()   # a launch's run key: goals signed like papf goal's

    def on_client(self, topic: str, data: bytes) -> None:
        """A client's message on ``topic``: a parameter outcome logged, a goal sent."""
        if topic == "/params/refused":
            self._note(LOG_WARNING, f"parameter change refused: {data.decode()}")
        elif topic == "/params/set":
            self._note(LOG_INFO, f"parameters set: {data.decode()}")
        elif topic in GOAL_TOPICS:
            xy = goal_from_client(data)
            if xy is None:
                self._note(LOG_WARNING, f"{topic}: no pose or point in {data[:80]!r}")
            elif not self.accept_goals:
                self._note(LOG_WARNING, f"goal ({xy[0]:.2f}, {xy[1]:.2f}) refused: this lockstep "
                           "run keeps its world's goal (runs stay deterministic); use papf launch")
            else:
                self._send_goal(*xy)
        elif topic:
            self._note(LOG_WARNING, f"{topic}: not a goal topic ({', '.join(GOAL_TOPICS)})")

    def _send_goal(self, x: float, y: float) -> None:
        core = self.core
        if core.goal is not None:   # keeps the tolerance and the road of the run's goal
            goal = dataclasses.replace(core.goal, stamp_ns=core.last_ns, x=x, y=y)
        else:
            goal = Goal(stamp_ns=core.last_ns, x=x, y=y,
                        tolerance=core.world.tolerance if core.world else 0.1)
        self.node.publish("goal", runauth.sign(goal, self.key))   # the launcher's planner is keyed
        self._note(LOG_INFO, f"goal set from the viewer: ({x:.2f}, {y:.2f})")

    def _note(self, level: int, message: str) -> None:
        self.node.log.log(logging.WARNING if level >= LOG_WARNING else logging.INFO, "%s", message)
        self.channels.log(*self.core.note(level, message))

    def run(self) -> None:
        """Convert every bus message to Foxglove until stopped; the static scene now and then."""
        next_static = 0.0
        for topic, msg in self.node.messages(tick_s=0.1):
            if topic == CLIENT:
                self.on_client(*msg)
            elif topic is not None:
                self.channels.log_all(self.core.on_message(topic, msg))
            now = time.monotonic()
            if now >= next_static:
                next_static = now + STATIC_EVERY_S
                self.channels.log_all(self.core.static_outputs())


def check_exposure(args: argparse.Namespace) -> None:
    """ConfigError unless goals and parameter changes come from this host only.

    Foxglove's WebSocket protocol has no authentication: whoever connects may publish goals
    and set parameters, which this viewer passes on signed with the run's key. On a loopback
    ``--host`` (the default, 127.0.0.1) that is this host's users, like ``papf goal``; on any
    other address it would be anyone who can reach the port, so there both must be refused
    (``--goals refuse --params refuse``: watching only); to steer from another machine, serve
    on 127.0.0.1 and reach it through an SSH tunnel (docs/viewer.md)."""
    if _loopback(args.host) or (args.goals == "refuse" and args.params == "refuse"):
        return
    raise ConfigError(f"--host {args.host!r}: the Foxglove WebSocket has no authentication, so "
                      "on an address other hosts reach give --goals refuse --params refuse "
                      "(watch only), or serve on 127.0.0.1 and use an SSH tunnel to steer")


def _loopback(host: str) -> bool:
    import ipaddress

    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:   # a host name: it may resolve to anything
        return False


def serve(args: argparse.Namespace, log: logging.Logger) -> int:
    """Serve ``args``' namespace to Foxglove; the exit code."""
    check_exposure(args)
    world = load_world(args.world) if args.world else None
    try:
        with open_node(NAME, args, log) as node:
            return _serve(node, args, world, log)
    except zenoh.ZError as exc:
        raise PapfError(f"cannot reach the Zenoh network ({exc}); is a router running? "
                        "(papf run/launch start one; or python -m papf.launch.router)") from None


def _serve(node: Node, args: argparse.Namespace, world, log: logging.Logger) -> int:
    listener = Listener(node, log, args.params == "accept")
    context = foxglove.Context()
    channels = FoxgloveChannels(context)
    try:
        server = foxglove.start_server(
            name=f"papf-stack {args.namespace}", host=args.host, port=args.port,
            capabilities=[Capability.ClientPublish, Capability.Parameters],
            supported_encodings=["json"], server_listener=listener, context=context)
    except Exception as exc:  # the SDK raises its own error type for a taken port
        raise PapfError(f"cannot serve on {args.host}:{args.port}: {exc}") from None
    try:
        for topic in SUBSCRIBED:
            node.subscribe(topic)
        node.declare_publishers("goal")
        node.ready()
        log.info("Foxglove WebSocket on ws://%s:%d (goals: %s)", args.host, server.port,
                 args.goals)
        Viewer(node, ViewCore(world), channels, args.goals == "accept").run()
    finally:
        server.stop()
        channels.close()
    return 0


def main(argv=None) -> int:
    """``python -m nodes.viewer``: serve; the exit code (2 on a bad setting)."""
    args = parse_args(argv)
    log = setup_logging(NAME, args.log_level)
    try:
        return serve(args, log)
    except PapfError as exc:
        log.error("%s", exc)
        return 2


if __name__ == "__main__":
    sys.exit(main())
