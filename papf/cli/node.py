"""``papf node list|info``: the nodes on the bus and their ports (like ``ros2 node``).

Our nodes by their liveliness tokens (``<ns>/alive/<node>``), their ports from
``nodes/<node>/ports.py``; the ROS 2 nodes behind each reachable zenoh-bridge-ros2dds (its
admin space, ``--ros bridge``, the default) or, with ``--ros rmw_zenoh``, the ROS 2 nodes of
``--ros-domain`` (a robot's, the stack's face) by rmw_zenoh's tokens, with their
publishers, subscriptions and services. The work is :mod:`papf.bus.graph`.
"""

from __future__ import annotations

import sys

from common.ros_link import add_ros_args, ros_domain
from common.text import safe_text
from common.transport import add_zenoh_args
from schemas import Keys


def register(sub) -> None:
    """Add ``papf node list|info`` and their options to the subcommands ``sub``."""
    p = sub.add_parser("node", help="list the nodes on the bus, show one's ports (like ros2 node)",
                       description="Our nodes (liveliness) and the ROS 2 nodes behind "
                                   "zenoh-bridge-ros2dds (its admin space) or, with --ros "
                                   "rmw_zenoh, of a domain (rmw_zenoh's liveliness tokens).")
    nsub = p.add_subparsers(dest="node_command", required=True, metavar="list|info")
    q = nsub.add_parser("list", help="our alive nodes and the ROS 2 nodes (bridge or rmw_zenoh)")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_node_list)
    q = nsub.add_parser("info", help="a node's ports: ours by name (planner), a ROS 2 node by its "
                                     "full name (/rosbot_emulator; on rmw_zenoh with --ros "
                                     "rmw_zenoh)")
    q.add_argument("name", metavar="NAME")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_node_info)


def _session(args):
    from papf.bus.session import open_session  # zenoh: only when connecting

    return open_session(args)


def cmd_node_list(args) -> int:
    """``papf node list``: our alive nodes (and ROS 2 nodes with ``--ros``); the exit code."""
    from common.transport import alive_nodes
    from papf.bus.graph import bridge_nodes, ros_entities, ros_nodes

    domain = ros_domain(args)
    keys = Keys(args.namespace)
    with _session(args) as s:
        ours = sorted(alive_nodes(s, keys))
        if args.ros == "rmw_zenoh":
            ros = [f"{n}  (ROS 2, rmw_zenoh domain {domain})"
                   for n in ros_nodes(ros_entities(s, domain))]
        else:
            ros = [f"{n.name}  (ROS 2, zenoh-bridge-ros2dds {n.bridge[:8]})"
                   for n in bridge_nodes(s)]
    for name in ours:   # names as peers announced them: shown, never run (common.text)
        print(f"{keys.ns}/{safe_text(name, 120)}")
    for line in ros:
        print(safe_text(line, 200))
    if not ours and not ros:
        where = (f"ROS domain {domain}" if args.ros == "rmw_zenoh"
                 else "any zenoh-bridge-ros2dds's admin space")
        print(f"no node alive under {keys.alive()} nor in {where}", file=sys.stderr)
    return 0


def cmd_node_info(args) -> int:
    """``papf node info``: a node's ports; the exit code."""
    from common.transport import alive_nodes
    from papf.bus.graph import describe_port, node_ports

    keys = Keys(args.namespace)
    domain = ros_domain(args)
    if args.name.startswith("/"):
        return _ros_node_info(args, domain)
    ports = node_ports(args.name)
    with _session(args) as s:
        alive = args.name in alive_nodes(s, keys)
    if ports is None and not alive:
        print(f"papf node info: no node {args.name!r} (papf node list shows the alive ones)",
              file=sys.stderr)
        return 2
    print(f"{keys.ns}/{args.name}: {'alive' if alive else 'not alive'}")
    if ports is None:
        print("  (declares no ports: a tool, not a stack node)")
        return 0
    for variant, declared in ports.variants.items():
        print(f"  ports{' with ' + variant if variant else ''}:")
        for port in declared:
            print(f"    {describe_port(port, keys.ns)}")
    return 0


def _ros_node_info(args, domain: int) -> int:
    """``papf node info /name``: from rmw_zenoh's tokens or the bridges' admin space."""
    from papf.bus.graph import bridge_nodes, ros_entities, ros_node_info, ros_nodes

    with _session(args) as s:
        if args.ros == "rmw_zenoh":
            entities = ros_entities(s, domain)
            info = ros_node_info(entities, args.name)
            found = args.name in ros_nodes(entities)
            lines = {role: [f"{e.topic}: {e.typename} ({e.qos.describe()})" for e in entities]
                     for role, entities in info.items()}
            where = f"in rmw_zenoh domain {domain}"
        else:
            nodes = [n for n in bridge_nodes(s) if n.name == args.name]
            found = bool(nodes)
            lines = {role.replace("_", " "): sorted({f"{name}: {ty}" for n in nodes
                                                      for name, ty in n.interfaces[role]})
                     for role in nodes[0].interfaces} if nodes else {}
            where = "behind any zenoh-bridge-ros2dds (none answered for it)"
    if not found:
        print(f"papf node info: no ROS 2 node {args.name} {where} (papf node list"
              f"{' --ros rmw_zenoh' if args.ros == 'rmw_zenoh' else ''} shows them)",
              file=sys.stderr)
        return 2
    print(args.name)
    for role, items in lines.items():
        if items or role in ("publishers", "subscriptions", "subscribers"):
            print(f"  {role.capitalize()}:")
            for item in items:
                print(f"    {safe_text(item, 200)}")
    return 0
