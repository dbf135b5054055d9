"""Planner node: ``python -m nodes.planner --planner apf|papf|arapf|wang|iapf [options]``.

Ports: :mod:`nodes.planner.ports` (``--help`` prints them).

Settings: ``--planner`` (algorithm), ``--params FILE.toml`` and ``--set name=value``
(see docs/planners.md for every parameter), ``--realtime`` (pair scans with the latest
odometry instead of the same stamp), ``--stale-timeout S`` (zero command when odometry
or scans are older than that), ``--pair-timeout S`` (lockstep: wall time a scan waits for
its odometry), ``--objects`` (take obstacle tracks from ``<ns>/objects``, sim ground
truth or the tracker node, and wait for the scan's own in lockstep), ``--passing orca``
(a fleet's robots pass each other: the reciprocal layer of :mod:`nodes.planner.passing` over
the command, fed by the obstacle tracks), ``--robots r1,r2,...`` (one process plans for a sim
fleet: a planner and a loop per robot, each robot's keys, seals, stamps, token and parameters
its own, as a process of its own would have them), plus the Zenoh options of :func:`common.transport.add_zenoh_args`.
Exit code 2 on a bad setting.
"""

from __future__ import annotations

import argparse
import json
import logging
import time

from common import runauth, seal
from common.cliparse import ArgumentParser
from common.errors import ConfigError
from common.params import arg_type
from common.ports import describe, plain
from common.transport import Node, add_zenoh_args, exit_fast, fleet_names, open_node, setup_logging
from common.units import LOCKSTEP_PAIR_TIMEOUT_S
from nodes.planner import lazy
from nodes.planner.loop import PLAN_HORIZON_S, PlannerLoop
from nodes.planner.params import answer
from nodes.planner.passing import MODES, Passing, PassingParams
from nodes.planner.ports import EXTRAS, PORTS, VARIANTS
from nodes.planner.registry import DEFAULT_PLANNER, PLANNERS, PRESETS, make_planner, preset_sets
from nodes.planner.settings import NODE
from schemas.messages import Event

NODE_NAME = "planner"


def parse_args(argv=None) -> argparse.Namespace:
    """The node's command line (``python -m nodes.planner --help``)."""
    ap = ArgumentParser(prog="python -m nodes.planner", description=plain(__doc__.split("\n")[0]),
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=describe(PORTS, VARIANTS, EXTRAS))
    ap.add_argument("--planner", default=DEFAULT_PLANNER, choices=sorted(PLANNERS), help="algorithm")
    ap.add_argument("--params", metavar="FILE.toml", help="planner settings file")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="override one setting, repeatable (e.g. --set d_o=0.8)")
    ap.add_argument("--preset", choices=PRESETS, default="default",
                    help="default (our improvements) or paper (the paper read literally)")
    ap.add_argument("--realtime", action="store_true",
                    help="pair each scan with the latest odometry (robot / HIL)")
    ap.add_argument("--stale-timeout", type=arg_type("--stale-timeout", NODE["stale_timeout"]),
                    default=0.5, metavar="S",
                    help="inputs older than this -> zero command [s] (default 0.5)")
    ap.add_argument("--pair-timeout", type=arg_type("--pair-timeout", NODE["pair_timeout"]),
                    default=LOCKSTEP_PAIR_TIMEOUT_S, metavar="S",
                    help="lockstep: wall time a scan waits for its odometry [s] (default "
                         f"{LOCKSTEP_PAIR_TIMEOUT_S:g}, longer than the driver's --lockstep-timeout)")
    ap.add_argument("--plan-horizon", type=arg_type("--plan-horizon", NODE["plan_horizon"]),
                    default=PLAN_HORIZON_S, metavar="S",
                    help="realtime: the short plan each command carries for the robot to follow "
                         f"on a slow link [s] (default {PLAN_HORIZON_S:g}; docs/link-driving.md)")
    ap.add_argument("--objects", action="store_true",
                    help="subscribe to <ns>/objects and pair each scan with its obstacle tracks")
    ap.add_argument("--passing", choices=MODES, default="off",
                    help="orca: pass the robots and people of the obstacle tracks (a fleet; needs "
                         "--objects), off: the planner's command as it is (default)")
    ap.add_argument("--robots", metavar="R1,R2,...",
                    help="one process plans for these robots, each on its own namespace (a sim "
                         "fleet; the launch profile's fleet = \"one\")")
    ap.add_argument("--log-level", default="INFO")
    add_zenoh_args(ap)
    args = ap.parse_args(argv)
    try:
        args.names = fleet_names(args.robots)   # [""]: the one robot of --namespace
    except ConfigError as exc:
        ap.error(str(exc))
    if args.passing != "off" and not args.objects:
        ap.error(f"--passing {args.passing} needs --objects (the other robots come as obstacle tracks)")
    return args


POLL_ALL_S = 0.05   # [s] a fleet's process looks at every robot's overdue pairings this often


class RobotLog(logging.LoggerAdapter):
    """The process's log, each line led by the robot's name (``r3: status reached …``)."""

    def process(self, msg, kwargs):
        return f"{self.extra['robot']}: {msg}", kwargs


class Served:
    """One robot a planner process serves: its :class:`Node` (the process's own, or a share of
    its session with the robot's keys, seals, stamps and token), its planner and its loop."""

    def __init__(self, node: Node, name: str, planner, args: argparse.Namespace, log):
        self.planner = planner
        log = RobotLog(log, {"robot": name}) if name else log   # a fleet's lines name the robot
        self.share = share = node.share(name, log)
        self.loop = PlannerLoop(planner, args.realtime, args.stale_timeout, args.pair_timeout, log,
                                runauth.key_from_env(), objects=args.objects,
                                send_command=lambda cmd: share.publish("cmd_vel", cmd),
                                want_state=lambda: share.listened("planner/state"),
                                plan_horizon_s=args.plan_horizon)
        prefix = f"{name}/" if name else ""   # how its items come out of the process's loop
        for topic in ("scan", "goal"):
            share.subscribe(topic, handler=lambda m, t=prefix + topic: node.inbox.put((t, m)))
        # the scan's partners too, each a wake: batched in Zenoh's channel, odom(t) or
        # objects(t) now and then reached the loop only with the next scan, on a loaded
        # machine, and held the lockstep (docs/architecture.md, "Lockstep")
        for topic in ("odom", "objects") if args.objects else ("odom",):
            share.subscribe(topic, handler=lambda m, t=prefix + topic: node.inbox.put((t, m)))
        share.declare_publishers("cmd_vel", "planner/status", "events",
                                 on_demand=("planner/state",))
        self.params_q = node.session.declare_queryable(  # answered on the loop's thread, in order
            share.keys.key("planner/params"),
            lambda q, t=prefix + "planner/params": node.inbox.put((t, q)))
        self.last_status = None

    def publish(self, out: list) -> None:
        for topic, msg in out:
            self.share.publish(topic, msg)
            if topic == "planner/status" and msg.state != self.last_status:
                self.last_status = msg.state
                self.share.log.info("status %s at %d ns %s", msg.state, msg.stamp_ns, msg.reason)

    def close(self, node: Node) -> None:
        self.params_q.undeclare()
        if self.share is not node:
            self.share.close()


def build_planner(args: argparse.Namespace):
    """The planner of ``args`` (ConfigError: a bad setting), warmed up."""
    planner = make_planner(args.planner, args.params, [*preset_sets(args.preset), *args.set])
    if args.passing != "off":
        planner.passing = Passing(PassingParams(mode=args.passing))
    warm_up(planner)
    return planner


def run(args: argparse.Namespace) -> int:
    """Open the session, build the planner (one per robot of ``--robots``), serve scans until
    stopped; the exit code."""
    log = setup_logging(NODE_NAME, args.log_level)
    # numba would import scipy.linalg for nothing (nodes/planner/lazy.py); a library's kernels
    # (pysocialforce's, the social-force planner's) use np.dot and need it
    if not getattr(PLANNERS.get(args.planner), "needs_blas", False):
        lazy.numba_without_scipy()
    try:
        planners = {name: build_planner(args) for name in args.names}
    except ConfigError as exc:
        log.error("%s", exc)
        return 2
    fleet = args.names != [""]
    with open_node(NODE_NAME, args, log) as node:
        served = {name: Served(node, name, planner, args, log) for name, planner in planners.items()}
        for robot in served.values():
            if robot.share is not node:
                robot.share.ready()
        node.ready()   # in a fleet, <namespace>/alive/planner too: the process itself is up
        params_check = runauth.RequestCheck(runauth.key_from_env(), seal.run_from_env())
        log.info("planner %s (%s) for %s; waiting for a goal (papf goal X Y)", args.planner,
                 "realtime" if args.realtime else "lockstep",
                 ", ".join(served) if fleet else node.keys.goal)
        polled = time.monotonic()
        for topic, msg in node.messages(tick_s=0.05):
            now = time.monotonic()
            name, topic = topic.split("/", 1) if fleet and topic else ("", topic)
            robot = served.get(name)
            if topic == "planner/params":
                _answer_params(robot.share, args.planner, robot.planner, msg, robot.loop.last_stamp,
                               params_check)
                continue
            if robot is not None and topic:
                robot.publish(robot.loop.on_message(topic, msg, now) + robot.loop.poll(now))
            if topic is None or now - polled >= POLL_ALL_S:   # the others' overdue pairings
                polled = now
                for other in served.values():
                    other.publish(other.loop.poll(now))
        for robot in served.values():
            robot.share.log.info("stopping after %d cycles (%d stale)", robot.loop.cycles,
                                 robot.loop.stale_cycles)
            robot.close(node)
    return 0


def _answer_params(node, name: str, planner, query, stamp_ns: int, check) -> None:
    """Reply to a ``planner/params`` query; a change is logged and published as an event."""
    payload = query.payload.to_bytes() if query.payload is not None else b""
    reply, changed = answer(name, planner, payload, check)
    query.reply(query.key_expr, json.dumps(reply).encode())
    query.drop()   # final now: a querier consolidating replies gets it now, not at its timeout
    if reply["error"]:
        node.log.warning("parameter change refused: %s", reply["error"])
    if changed:
        detail = "parameters set: " + ", ".join(f"{k}={reply['params'][k]}" for k in changed)
        node.log.info("%s", detail)
        node.publish("events", Event(stamp_ns=stamp_ns, kind="info", source="planner",
                                     detail=detail))


def warm_up(planner) -> None:
    """Compile (or load) the JIT kernels before ``ready``: the scan view every planner uses
    and the strategy's own, so the first lockstep cycle is not late."""
    planner.warm_up()


def main(argv=None) -> int:
    """``python -m nodes.planner``: parse, run, exit code (2 on a bad option)."""
    return run(parse_args(argv))


if __name__ == "__main__":
    exit_fast(main())   # the session is closed: skip the interpreter's slow teardown
