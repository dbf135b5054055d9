"""The emulated ROSbot's node as zenoh-bridge-ros2dds tells it in its admin space.

A real bridge answers queries on ``@/<bridge zid>/ros2/node/**`` with one JSON object per
ROS 2 node it discovered on DDS (eclipse-zenoh/zenoh-plugin-ros2dds @09d68c0: ``lib.rs``
line 131, ``discovered_entities.rs`` line 41; the node id ``<participant GID hex>[/<ns>]/<name>``
of ``node_info.rs`` lines 414-462; the value of lines 360-392). ``papf rosbot-emulator
--ros bridge`` plays robot and bridge in one process, so it answers the same way for its
own node: ``papf node list`` and ``papf topic info /cmd_vel`` then see it as they would see
the ROSbot's nodes behind a real bridge. Read by :mod:`papf.bus.graph`.
"""

from __future__ import annotations

import json

import zenoh


def node_key(bridge_zid: str, participant: str, namespace: str, name: str) -> str:
    """``@/<zid>/ros2/node/<gid>[/<ns>]/<name>`` (the namespace ``/`` adds nothing)."""
    ns = namespace.strip("/")
    return f"@/{bridge_zid}/ros2/node/{participant}/" + (f"{ns}/{name}" if ns else name)


def node_json(publishers: dict[str, str], subscribers: dict[str, str]) -> bytes:
    """The bridge's ``NodeInfo`` JSON of a node with these topics (ROS name -> ROS type), byte
    for byte as serde_json writes it (fields in declaration order, no spaces)."""
    def items(topics: dict[str, str]) -> list[dict[str, str]]:
        return [{"name": n, "type": t} for n, t in sorted(topics.items())]

    return json.dumps({"publishers": items(publishers), "subscribers": items(subscribers),
                       "service_servers": [], "service_clients": [], "action_servers": [],
                       "action_clients": []}, separators=(",", ":")).encode()


class BridgeAdmin:
    """A queryable on ``@/<zid>/ros2/**`` that answers for one node (until :meth:`close`)."""

    def __init__(self, session: zenoh.Session, name: str, publishers: dict[str, str],
                 subscribers: dict[str, str], namespace: str = "/"):
        zid = str(session.info.zid())
        self.key = node_key(zid, zid.rjust(32, "0"), namespace, name)
        self.value = node_json(publishers, subscribers)
        self._ke = zenoh.KeyExpr(self.key)
        self.queryable = session.declare_queryable(f"@/{zid}/ros2/**", self._on_query)

    def _on_query(self, query: zenoh.Query) -> None:
        if zenoh.KeyExpr(str(query.key_expr)).intersects(self._ke):
            query.reply(self.key, self.value, encoding=zenoh.Encoding.APPLICATION_JSON)

    def close(self) -> None:
        self.queryable.undeclare()
