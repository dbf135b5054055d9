"""``papf node list|info``: the nodes on the bus and their ports (like ``ros2 node``).

Our nodes by their liveliness tokens (``<ns>/alive/<node>``), their ports from
``nodes/<node>/ports.py``; with ``--ros rmw_zenoh`` also the ROS 2 nodes of ``--ros-domain``
(a robot's, the stack's face) by rmw_zenoh's tokens, with their publishers and
subscriptions. The work is :mod:`papf.bus.graph`.
"""

from __future__ import annotations

import sys

from common.ros_link import add_ros_args, ros_domain
from common.transport import add_zenoh_args
from schemas import Keys


def register(sub) -> None:
    """Add ``papf node list|info`` and their options to the subcommands ``sub``."""
    p = sub.add_parser("node", help="list the nodes on the bus, show one's ports (like ros2 node)",
                       description="Our nodes (liveliness) and, with --ros rmw_zenoh, the ROS 2 "
                                   "nodes of a domain (rmw_zenoh's liveliness tokens).")
    nsub = p.add_subparsers(dest="node_command", required=True, metavar="list|info")
    q = nsub.add_parser("list", help="our alive nodes (and ROS 2 nodes with --ros rmw_zenoh)")
    add_ros_args(q, cmd_vel=False)
    add_zenoh_args(q)
    q.set_defaults(func=cmd_node_list)
    q = nsub.add_parser("info", help="a node's ports: ours by name (planner), a ROS 2 node by its "
                                     "full name (/papf_planner, with --ros rmw_zenoh)")
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
    from papf.bus.graph import ros_entities, ros_nodes

    domain = ros_domain(args)
    keys = Keys(args.namespace)
    with _session(args) as s:
        ours = sorted(alive_nodes(s, keys))
        ros = ros_nodes(ros_entities(s, domain)) if args.ros == "rmw_zenoh" else None
    for name in ours:
        print(f"{keys.ns}/{name}")
    if ros is not None:
        for name in ros:
            print(f"{name}  (ROS 2, rmw_zenoh domain {domain})")
    if not ours and not ros:
        print(f"no node alive under {keys.alive()}" + (f" nor in ROS domain {domain}"
                                                       if ros is not None else ""), file=sys.stderr)
    return 0


def cmd_node_info(args) -> int:
    """``papf node info``: a node's ports; the exit code."""
    from common.transport import alive_nodes
    from papf.bus.graph import describe_port, node_ports, ros_entities, ros_node_info

    keys = Keys(args.namespace)
    domain = ros_domain(args)
    if args.name.startswith("/"):
        if args.ros != "rmw_zenoh":
            print("papf node info: a ROS 2 node (/name) needs --ros rmw_zenoh (the bridge "
                  "announces no ROS graph on Zenoh: use ros2 node info on the robot)", file=sys.stderr)
            return 2
        with _session(args) as s:
            info = ros_node_info(ros_entities(s, domain), args.name)
        if not any(info.values()):
            print(f"papf node info: no ROS 2 node {args.name} in domain {domain} (papf node list "
                  "--ros rmw_zenoh shows them)", file=sys.stderr)
            return 2
        print(args.name)
        for role, entities in info.items():
            print(f"  {role.capitalize()}:")
            for e in entities:
                print(f"    {e.topic}: {e.typename} ({e.qos.describe()})")
        return 0
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
