"""The client side of a node's live parameter query (``<ns>/planner/params``, JSON;
:mod:`nodes.planner.params` answers it): one request, its reply. Used by ``papf param``
and the ROS 2 face's parameter services."""

from __future__ import annotations

import json

import zenoh


def ask(session, key: str, request: dict, timeout_s: float) -> dict | None:
    """The node's reply to ``request`` on ``key`` (a dict with ``params``), or None when no
    answer came within ``timeout_s``. Replies are not consolidated: the first good one is
    taken as soon as it arrives."""
    for reply in session.get(key, payload=json.dumps(request).encode(),
                             consolidation=zenoh.ConsolidationMode.NONE, timeout=timeout_s):
        if reply.ok is None:
            continue
        try:
            out = json.loads(reply.ok.payload.to_bytes())
        except ValueError:
            continue
        if isinstance(out, dict) and isinstance(out.get("params"), dict):
            return out
    return None
