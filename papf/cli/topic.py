"""``papf topic list|echo|hz``: what the bus carries, what it says, how often (like ``ros2 topic``).

Takes the Zenoh options every node takes (``--connect``, ``--mode``, ``--namespace``,
``--zenoh-config`` …), so it reaches whatever the nodes reach: the embedded router of
``papf run``/``papf launch`` by default, a robot with ``--connect tcp/<robot>:7447``, a
secure split with ``--zenoh-config``. The work is :mod:`papf.bus.topics`.
"""

from __future__ import annotations

import argparse
import sys

from common.params import RATE_HZ, TIMEOUT, arg_type, integer, num
from common.ros_link import add_ros_args, ros_distro, ros_domain
from common.transport import StopRequested, add_zenoh_args
from schemas import Keys

TOPIC_EPILOG = """\
KEY: a stack topic without the namespace (scan, odom, planner/state) gets it
(rosbot/scan); a leading / names a ROS 2 topic (/scan, /odometry/filtered): the bridge's
key, or with --ros rmw_zenoh rmw_zenoh's key in --ros-domain; anything else is a Zenoh
key expression used as given (rosbot/**, lab/r1/odom, 0/**).
Our messages are decoded by their msgpack type, rmw_zenoh's CDR by the type its key
names, the bridge's CDR by the key (cmd_vel, odometry/filtered, battery, scan, imu/data,
joint_states, tf) or --ros-type."""


def register(sub) -> None:
    """Add ``papf topic list|echo|hz|pub|info`` and their options to the subcommands ``sub``."""
    p = sub.add_parser("topic", help="list, echo and measure the bus's topics (like ros2 topic)",
                       description="Poke the bus: what is published, what it says, how often.")
    tsub = p.add_subparsers(dest="topic_command", required=True,
                            metavar="list|echo|hz|pub|info")
    q = tsub.add_parser("list", help="keys heard, with type, encoding and rate; nodes alive",
                        description="Listen to every key for --duration seconds and list what "
                                    "arrived (plus the stack's silent topics and live nodes).")
    q.add_argument("--duration", type=arg_type("--duration", TIMEOUT), default=2.0, metavar="S",
                   help="how long to listen [s] (default 2)")
    q.add_argument("--json", action="store_true", help="one JSON object per key")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_topic_list, namespace=None)   # none given: the whole fleet
    q = tsub.add_parser("echo", help="print the messages on a key", epilog=TOPIC_EPILOG,
                        formatter_class=argparse.RawDescriptionHelpFormatter,
                        description="Print each message on KEY, decoded (until Ctrl-C or --count).")
    q.add_argument("key", metavar="KEY")
    add_stop_options(q, "messages printed")
    q.add_argument("--timeout", type=arg_type("--timeout", num(0.0, 1e6, "s")), default=0.0, metavar="S",
                   help="exit 5 if no message came within S seconds (default: wait forever)")
    q.add_argument("--full", action="store_true", help="print whole arrays (default: first 8)")
    q.add_argument("--json", action="store_true", help="one JSON object per message")
    q.add_argument("--ros-type", metavar="TYPE", help="decode CDR as this ROS 2 type "
                   "(e.g. sensor_msgs/msg/LaserScan) instead of guessing from the key")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_topic_echo)
    q = tsub.add_parser("hz", help="print the rate of a key in Hz", epilog=TOPIC_EPILOG,
                        formatter_class=argparse.RawDescriptionHelpFormatter,
                        description="Print the rate of the messages on KEY every second: by "
                                    "arrival (wall clock) and by the messages' own stamps "
                                    "(sim time in a lockstep simulation).")
    q.add_argument("key", metavar="KEY")
    q.add_argument("--window", type=arg_type("--window", integer(2, 1_000_000)), default=1000, help="messages in the statistics (1000)")
    add_stop_options(q, "messages heard", once="print one report (after 1 s) and exit")
    q.add_argument("--ros-type", metavar="TYPE", help="ROS 2 type of CDR payloads (stamps)")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_topic_hz)
    q = tsub.add_parser("pub", help="publish a message typed as YAML/JSON (like ros2 topic pub)",
                        epilog=TOPIC_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
                        description="Publish VALUE (the message's fields as YAML or JSON, e.g. "
                                    "\"{v: 0.2, w: 0.0}\" or \"{linear: {x: 0.2}}\") on KEY; "
                                    "fields not given take their defaults.")
    q.add_argument("key", metavar="KEY")
    q.add_argument("value", metavar="VALUE", nargs="?", default="{}")
    add_stop_options(q, "messages published", times=True)
    q.add_argument("--rate", "-r", type=arg_type("--rate", RATE_HZ), default=1.0, metavar="HZ", help="rate (1 Hz)")
    q.add_argument("--ros-type", metavar="TYPE", help="ROS 2 type of a /topic (default: the "
                   "ROSbot's type of that topic)")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_topic_pub)
    q = tsub.add_parser("info", help="publishers and subscribers of a key (like ros2 topic info)",
                        epilog=TOPIC_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
                        description="Our keys: the alive nodes that declare it as an output or "
                                    "input. A ROS 2 /topic: its publishers and subscribers as "
                                    "zenoh-bridge-ros2dds's admin space tells them, or with --ros "
                                    "rmw_zenoh from rmw_zenoh's liveliness tokens.")
    q.add_argument("key", metavar="KEY")
    q.add_argument("--verbose", "-v", action="store_true", help="types, QoS and GIDs too")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_topic_info)


def add_stop_options(q, what: str, once: str = "", times: bool = False) -> None:
    """``--once``, ``--count N``, ``--duration S``: how every topic tool that would run until
    Ctrl-C stops, alike (the first of them reached ends it). ``times``: ``--times``/``-t``
    is ``--count`` too (ros2 topic pub's name)."""
    names = ("--count", "-n", "--times", "-t") if times else ("--count", "-n")
    q.add_argument("--once", "-1", action="store_true", help=once or "the same as --count 1")
    q.add_argument(*names, dest="count", type=arg_type("--count", integer(0, None)), default=0,
                   metavar="N", help=f"stop after N {what} (default: no limit)")
    q.add_argument("--duration", type=arg_type("--duration", num(0.0, 1e6, "s")), default=0.0,
                   metavar="S", help="stop after S seconds (default: no limit; with none of "
                                     "--once, --count, --duration: until Ctrl-C)")


def _session(args):
    from papf.bus.session import open_session  # zenoh: only when connecting

    return open_session(args)


def _out(line: str) -> None:
    try:
        print(line, flush=True)
    except BrokenPipeError:   # `papf topic echo … | head`: the reader is done, so are we
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        raise SystemExit(0) from None


def _key(args) -> str:
    """KEY resolved (see TOPIC_EPILOG); a bad --ros-domain is a usage error (exit 2)."""
    from papf.bus.topics import resolve_key

    return resolve_key(args.key, Keys(args.namespace), args.ros, ros_domain(args))


def cmd_topic_list(args) -> int:
    """``papf topic list``: keys heard with type and rate, nodes alive; the exit code."""
    from papf.bus.topics import topic_list

    domain = ros_domain(args)
    stop = StopRequested()
    only = args.namespace is not None   # --namespace NS: that robot alone; else the fleet
    table = None
    if sys.stdout.isatty() and not args.json:   # a terminal: a table that fits it
        from papf.console.tables import print_table

        table = print_table
    with _session(args) as s:
        topic_list(s, Keys(args.namespace or "rosbot"), args.duration, _out, lambda: bool(stop),
                   args.json, only, table=table)
        if args.ros == "rmw_zenoh":   # the ROS 2 graph of the domain, from rmw_zenoh's tokens
            _ros_graph(s, domain, args.json)
    return 130 if stop else 0


def _ros_graph(session, domain: int, as_json: bool) -> None:
    import json

    from common import rmw_zenoh as rz
    from papf.bus.graph import ros_entities, ros_nodes

    entities = ros_entities(session, domain)
    topics = sorted({(e.topic, e.typename) for e in entities if e.kind in (rz.PUBLISHER,
                                                                           rz.SUBSCRIPTION)})
    if as_json:
        _out(json.dumps({"ros_domain": domain, "ros_nodes": ros_nodes(entities),
                         "ros_topics": [{"topic": t, "type": ty} for t, ty in topics]}))
        return
    _out(f"ROS 2 on rmw_zenoh, domain {domain}: nodes {', '.join(ros_nodes(entities)) or 'none'}")
    for topic, typename in topics:
        _out(f"  {topic}  [{typename}]")


def cmd_topic_echo(args) -> int:
    """``papf topic echo``: print the messages on a key; the exit code."""
    from papf.bus.topics import echo

    stop = StopRequested()
    key = _key(args)
    count = 1 if args.once else args.count
    with _session(args) as s:
        n = echo(s, key, _out, count=count, timeout_s=args.timeout, ros_type=args.ros_type,
                 max_items=None if args.full else 8, as_json=args.json, stop=lambda: bool(stop),
                 note=lambda line: print(f"papf topic echo: {line}", file=sys.stderr, flush=True),
                 duration_s=args.duration)
    if stop:
        return 130 if n == 0 else 0
    if n == 0:
        waited = min((t for t in (args.timeout, args.duration) if t > 0), default=0.0)
        print(f"papf topic echo: no message on {key} within {waited:g} s "
              "(papf topic list shows what is published)", file=sys.stderr)
        return 5
    return 0


def cmd_topic_hz(args) -> int:
    """``papf topic hz``: print a key's rate [Hz]; the exit code."""
    from papf.bus.topics import hz

    if args.window < 2:
        print("papf topic hz: --window must be at least 2 messages", file=sys.stderr)
        return 2
    stop = StopRequested()
    key = _key(args)
    with _session(args) as s:
        hz(s, key, _out, window=args.window, duration_s=args.duration, ros_type=args.ros_type,
           stop=lambda: bool(stop), count=args.count, reports=1 if args.once else 0)
    return 130 if stop else 0


def cmd_topic_pub(args) -> int:
    """``papf topic pub``: publish a message typed as YAML/JSON; the exit code."""
    from papf.bus.fields import parse_value
    from papf.bus.pub import prepare, publish

    times = 1 if args.once else args.count
    if times < 0 or not (args.rate > 0 and args.rate <= 1000):
        print("papf topic pub: --count must be >= 0 and --rate in (0, 1000] Hz", file=sys.stderr)
        return 2
    prepared = prepare(args.key, parse_value(args.value), Keys(args.namespace), args.ros_type)
    domain = ros_domain(args)
    stop = StopRequested()
    with _session(args) as s:
        publish(s, prepared, args.ros, domain, times, args.rate, _out, lambda: bool(stop),
                duration_s=args.duration, distro=ros_distro(args))
    return 130 if stop and times != 1 else 0


def cmd_topic_info(args) -> int:
    """``papf topic info``: publishers and subscribers of a key; the exit code."""
    from papf.bus.graph import our_topic_info, ros_entities, ros_topic_info
    from schemas.keys import TOPICS

    keys = Keys(args.namespace)
    domain = ros_domain(args)
    with _session(args) as s:
        if args.key in TOPICS:
            info = our_topic_info(s, keys, args.key)
            _out(f"Key: {keys.key(args.key)}\nType: {TOPICS[args.key].TYPE}")
            for role in ("publishers", "subscriptions"):
                names = info[role]
                _out(f"{role.capitalize()[:-1]} count: {len(names)}"
                     + "".join(f"\n  {n}" for n in names))
            return 0
        if not args.key.startswith("/"):
            print(f"papf topic info: {args.key!r}: give a stack topic ({', '.join(sorted(TOPICS))})"
                  " or a ROS 2 /topic (behind zenoh-bridge-ros2dds, or with --ros rmw_zenoh)",
                  file=sys.stderr)
            return 2
        topic = "/" + args.key.strip("/")
        if args.ros != "rmw_zenoh":
            return _bridge_topic_info(s, topic, args.verbose)
        info = ros_topic_info(ros_entities(s, domain), topic)
    types = sorted({e.typename for v in info.values() for e in v})
    _out(f"Topic: {topic} (rmw_zenoh, domain {domain})\nType: {', '.join(types) or '?'}")
    for role, entities in info.items():
        _out(f"{role.capitalize()[:-1]} count: {len(entities)}")
        for e in entities:
            _out(f"  {e.fq_node}" + (f"  [{e.typename}, {e.hash}, {e.qos.describe()}, gid "
                                     f"{e.gid.hex('.')}]" if args.verbose else ""))
    return 0


def _bridge_topic_info(session, topic: str, verbose: bool) -> int:
    """A ROS 2 topic's publishers and subscribers as the bridges' admin space tells them."""
    from papf.bus.graph import bridge_nodes, bridge_topic_info

    nodes = bridge_nodes(session)
    info = bridge_topic_info(nodes, topic)
    if not nodes:
        print("papf topic info: no zenoh-bridge-ros2dds answered on @/*/ros2/node/** (is the "
              "bridge reachable? on rmw_zenoh give --ros rmw_zenoh)", file=sys.stderr)
        return 2
    types = sorted({ty for v in info.values() for _, ty in v})
    _out(f"Topic: {topic} (behind zenoh-bridge-ros2dds)\nType: {', '.join(types) or '?'}")
    for role, entries in info.items():
        _out(f"{role.capitalize()[:-1]} count: {len(entries)}")
        for node, ty in entries:
            _out(f"  {node}" + (f"  [{ty}]" if verbose else ""))
    return 0
