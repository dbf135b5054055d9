"""Who is on the bus: our nodes and their ports, ROS 2 nodes from rmw_zenoh's tokens.

Our nodes by their liveliness tokens (:mod:`common.transport`) and declared ports
(:func:`node_ports`); ROS 2 nodes on rmw_zenoh by theirs (:func:`ros_entities`; nodes behind
the bridge announce nothing on Zenoh: ``ros2 node list`` on the robot shows them). Used by
``papf node list|info`` and ``papf topic info``.
"""

from __future__ import annotations

import importlib
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


def node_ports(name: str) -> NodePorts | None:
    """The declared ports of our node ``name`` (None: no ``nodes/<name>/ports.py``)."""
    try:
        mod = importlib.import_module(f"nodes.{name}.ports")
    except ModuleNotFoundError:
        return None
    variants = {"": tuple(mod.PORTS)}
    for (option, value), ports in getattr(mod, "VARIANTS", {}).items():
        variants[f"{option} {value}"] = tuple(ports)
    for flag, more in getattr(mod, "EXTRAS", {}).items():
        variants[f"+{flag}"] = tuple(more)
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


def ros_node_info(entities: list[rz.Entity], fq_node: str) -> dict[str, list[rz.Entity]]:
    """The publishers and subscriptions of ROS node ``fq_node``, by topic."""
    mine = [e for e in entities if e.fq_node == fq_node and e.kind != rz.NODE]
    return {"publishers": sorted((e for e in mine if e.kind == rz.PUBLISHER), key=lambda e: e.topic),
            "subscriptions": sorted((e for e in mine if e.kind == rz.SUBSCRIPTION),
                                    key=lambda e: e.topic)}


def ros_topic_info(entities: list[rz.Entity], topic: str) -> dict[str, list[rz.Entity]]:
    """The publishers and subscriptions of ROS ``topic``."""
    mine = [e for e in entities if e.topic == topic]
    return {"publishers": [e for e in mine if e.kind == rz.PUBLISHER],
            "subscriptions": [e for e in mine if e.kind == rz.SUBSCRIPTION]}


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
