"""Who is on the bus: our nodes and their ports, ROS 2 nodes from rmw_zenoh's tokens.

Our nodes by their liveliness tokens (:mod:`common.transport`) and declared ports
(:func:`node_ports`); ROS 2 nodes on rmw_zenoh by theirs (:func:`ros_entities`), and the
ROS 2 nodes behind ``zenoh-bridge-ros2dds`` from its admin space (:func:`bridge_nodes`).
Used by ``papf node list|info`` and ``papf topic info``.
"""

from __future__ import annotations

import importlib
import json
from dataclasses import dataclass

from common import rmw_zenoh as rz
from common.errors import SchemaError
from common.ports import BRIDGE, Port
from common.transport import alive_nodes
from schemas import Keys


@dataclass(frozen=True)
class NodePorts:
    name: str
    variants: dict[str, tuple[Port, ...]]     # "" (default) or "--driver rosbot" -> ports


# A liveliness name that more than one node package serves, each under the option that picks
# it: on the bus the world simulator stands where the robot's base driver stands
# (``<ns>/alive/base_driver``; ``python -m nodes.base_driver --driver sim`` hands over to it).
SERVED_BY = {"base_driver": {"--driver sim": "world_sim", "--driver rosbot": "base_driver"}}


def node_ports(name: str) -> NodePorts | None:
    """The declared ports of our node ``name`` (None: no ``nodes/<name>/ports.py``)."""
    variants: dict[str, tuple[Port, ...]] = {}
    for label, package in SERVED_BY.get(name, {"": name}).items():
        try:
            mod = importlib.import_module(f"nodes.{package}.ports")
        except ModuleNotFoundError:
            return None
        variants[label] = tuple(mod.PORTS)
        for (option, value), ports in getattr(mod, "VARIANTS", {}).items():
            variants[f"{label} {option} {value}".strip()] = tuple(ports)
        for flag, more in getattr(mod, "EXTRAS", {}).items():
            variants[f"{label} +{flag}".strip()] = tuple(more)
    return NodePorts(name, variants)


def ros_entities(session, domain: int, timeout_s: float = 1.0) -> list[rz.Entity]:
    """Every rmw_zenoh entity of ``domain`` whose token is alive (malformed ones skipped)."""
    out = []
    for reply in session.liveliness().get(rz.liveliness_subscription(domain), timeout=timeout_s):
        if reply.ok is None:
            continue
        try:
            out.append(rz.Entity.parse(str(reply.ok.key_expr)))
        except SchemaError:
            continue
    return out


def ros_nodes(entities: list[rz.Entity]) -> list[str]:
    """The fully qualified names of the ROS nodes among ``entities``, sorted."""
    return sorted({e.fq_node for e in entities if e.kind == rz.NODE})


RMW_ROLES = {"publishers": rz.PUBLISHER, "subscriptions": rz.SUBSCRIPTION,
             "service servers": rz.SERVICE, "service clients": rz.CLIENT}


def ros_node_info(entities: list[rz.Entity], fq_node: str) -> dict[str, list[rz.Entity]]:
    """A node's publishers, subscriptions, service servers and clients (NN/MP/MS/SS/SC tokens)."""
    mine = [e for e in entities if e.fq_node == fq_node and e.kind != rz.NODE]
    return {role: sorted((e for e in mine if e.kind == kind), key=lambda e: e.topic)
            for role, kind in RMW_ROLES.items()}


def ros_topic_info(entities: list[rz.Entity], topic: str) -> dict[str, list[rz.Entity]]:
    """The publishers and subscriptions of ROS ``topic``."""
    mine = [e for e in entities if e.topic == topic]
    return {"publishers": [e for e in mine if e.kind == rz.PUBLISHER],
            "subscriptions": [e for e in mine if e.kind == rz.SUBSCRIPTION]}


# -- zenoh-bridge-ros2dds's admin space --------------------------------------------------------
BRIDGE_NODES = "@/*/ros2/node/**"
BRIDGE_ROLES = ("publishers", "subscribers", "service_servers", "service_clients",
                "action_servers", "action_clients")


@dataclass(frozen=True)
class BridgeNode:
    """A ROS 2 node a bridge discovered on DDS, with its interfaces as (name, type) pairs."""

    bridge: str                                    # the bridge's Zenoh id
    participant: str                               # the node's DDS participant GID (hex)
    name: str                                      # fully qualified, "/ns/name"
    interfaces: dict[str, tuple[tuple[str, str], ...]]


def parse_bridge_node(key: str, payload: bytes) -> BridgeNode:
    """One admin-space reply (``@/<zid>/ros2/node/<gid>/<ns…>/<name>``, JSON) -> BridgeNode.

    The format (eclipse-zenoh/zenoh-plugin-ros2dds @09d68c0): ``lib.rs`` line 131
    ``@/${zenoh_id}/ros2/``, ``discovered_entities.rs`` line 41 ``node/${node_id:**}`` where
    the id is ``<participant GID hex><namespace>[/]<name>`` (``node_info.rs`` lines 414-462);
    the value the ``NodeInfo`` of lines 360-392: ``publishers``, ``subscribers``,
    ``service_servers``, ``service_clients``, ``action_servers``, ``action_clients``, each a
    list of ``{"name": "/cmd_vel", "type": "geometry_msgs/msg/Twist"}``."""
    parts = key.split("/")
    if len(parts) < 6 or parts[0] != "@" or parts[2:4] != ["ros2", "node"]:
        raise SchemaError(f"{key!r} is not a zenoh-bridge-ros2dds node key")
    try:
        value = json.loads(payload)
    except (ValueError, UnicodeDecodeError) as exc:
        raise SchemaError(f"{key}: not JSON ({exc})") from None
    if not isinstance(value, dict):
        raise SchemaError(f"{key}: expected a JSON object, got {type(value).__name__}")
    interfaces = {}
    for role in BRIDGE_ROLES:
        items = value.get(role, [])
        if not isinstance(items, list) or not all(
                isinstance(i, dict) and isinstance(i.get("name"), str)
                and isinstance(i.get("type"), str) for i in items):
            raise SchemaError(f"{key}: {role} is not a list of {{name, type}}")
        interfaces[role] = tuple(sorted((i["name"], i["type"]) for i in items))
    return BridgeNode(parts[1], parts[4], "/" + "/".join(parts[5:]), interfaces)


def bridge_nodes(session, timeout_s: float = 1.0) -> list[BridgeNode]:
    """Every ROS 2 node the reachable bridges discovered (malformed replies skipped)."""
    out = []
    for reply in session.get(BRIDGE_NODES, timeout=timeout_s):
        if reply.ok is None:
            continue
        try:
            out.append(parse_bridge_node(str(reply.ok.key_expr), reply.ok.payload.to_bytes()))
        except SchemaError:
            continue
    return sorted(out, key=lambda n: (n.name, n.bridge))


def bridge_topic_info(nodes: list[BridgeNode], topic: str) -> dict[str, list[tuple[str, str]]]:
    """(node, type) of each publisher and subscriber of ROS 2 ``topic`` behind the bridges."""
    out: dict[str, list[tuple[str, str]]] = {"publishers": [], "subscribers": []}
    for node in nodes:
        for role in out:
            out[role] += [(node.name, ty) for name, ty in node.interfaces[role] if name == topic]
    return out


def our_topic_info(session, keys: Keys, suffix: str) -> dict[str, list[str]]:
    """Our alive nodes that declare ``suffix`` as an output / input (any variant)."""
    out: dict[str, list[str]] = {"publishers": [], "subscriptions": []}
    for name in sorted(alive_nodes(session, keys)):
        ports = node_ports(name)
        if ports is None:
            continue
        flat = {p for variant in ports.variants.values() for p in variant}
        if any(d == "out" and k == suffix for d, k, _ in flat):
            out["publishers"].append(name)
        if any(d.startswith("in") and k in (suffix, "**") for d, k, _ in flat):
            out["subscriptions"].append(name)
    return out


def describe_port(port: Port, ns: str) -> str:
    """One line of ``papf node info``: direction, key (a bridged one as ``<ros>/...``), type."""
    direction, key, msg_type = port
    shown = f"<ros>/{key[len(BRIDGE):]}" if key.startswith(BRIDGE) else f"{ns}/{key}"
    return f"{direction:<4} {shown:<32} {msg_type}"
