"""A minimal Foxglove WebSocket protocol client for tests and the view benchmark.

Speaks the protocol as Foxglove's app does (https://github.com/foxglove/ws-protocol):
JSON text frames for ``serverInfo``/``advertise``/``subscribe``/``getParameters``/
``setParameters``/client ``advertise``; binary frames for message data (server: opcode 1,
subscription id u32, log time u64, payload; client: opcode 1, channel id u32, payload).
Built on the ``websockets`` library, synchronous API.
"""

from __future__ import annotations

import json
import struct
import time
from collections import defaultdict

from websockets.sync.client import connect

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]


class FoxgloveClient:
    def __init__(self, url: str, timeout_s: float = 10.0):
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                self._conn = connect(url, subprotocols=SUBPROTOCOLS, open_timeout=2.0,
                                     max_size=None)
                self.ws = self._conn.__enter__()
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)
        self.server_info: dict = {}
        self.channels: dict[int, dict] = {}         # channel id -> advertised channel
        self.by_sub: dict[int, dict] = {}           # subscription id -> channel
        self.messages: dict[str, list[tuple[int, bytes, float]]] = defaultdict(list)
        self.json_ops: list[dict] = []
        self._next_sub = 1

    def close(self) -> None:
        self._conn.__exit__(None, None, None)

    def pump(self, duration_s: float) -> None:
        """Receive for ``duration_s`` seconds, sorting what arrives."""
        deadline = time.monotonic() + duration_s
        while (left := deadline - time.monotonic()) > 0:
            try:
                frame = self.ws.recv(timeout=left)
            except TimeoutError:
                return
            self._take(frame)

    def _take(self, frame) -> None:
        if isinstance(frame, str):
            op = json.loads(frame)
            self.json_ops.append(op)
            if op.get("op") == "serverInfo":
                self.server_info = op
            elif op.get("op") == "advertise":
                for ch in op["channels"]:
                    self.channels[ch["id"]] = ch
            elif op.get("op") == "unadvertise":
                for cid in op["channelIds"]:
                    self.channels.pop(cid, None)
            return
        if frame[0] == 1:
            sub, log_time = struct.unpack_from("<IQ", frame, 1)
            ch = self.by_sub.get(sub)
            if ch is not None:
                self.messages[ch["topic"]].append((log_time, bytes(frame[13:]), time.time()))

    def wait_for(self, predicate, timeout_s: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout_s
        while not predicate():
            if time.monotonic() > deadline:
                return False
            self.pump(0.05)
        return True

    def topics(self) -> dict[str, dict]:
        return {ch["topic"]: ch for ch in self.channels.values()}

    def subscribe(self, topics) -> None:
        subs = []
        for ch in self.channels.values():
            if ch["topic"] in topics:
                sid = self._next_sub
                self._next_sub += 1
                self.by_sub[sid] = ch
                subs.append({"id": sid, "channelId": ch["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def advertise(self, channel_id: int, topic: str, schema_name: str) -> None:
        self.ws.send(json.dumps({"op": "advertise", "channels": [
            {"id": channel_id, "topic": topic, "encoding": "json", "schemaName": schema_name}]}))

    def publish(self, channel_id: int, obj: dict) -> None:
        self.ws.send(struct.pack("<BI", 1, channel_id) + json.dumps(obj).encode())

    def request(self, op: dict, answer_op: str, timeout_s: float = 10.0) -> dict | None:
        """Send a JSON op with an id; return the server's answer op carrying that id."""
        op = {**op, "id": f"req{time.monotonic_ns()}"}
        n = len(self.json_ops)
        self.ws.send(json.dumps(op))
        found: list[dict] = []

        def got() -> bool:
            found[:] = [o for o in self.json_ops[n:] if o.get("op") == answer_op
                        and o.get("id") == op["id"]]
            return bool(found)
        return found[0] if self.wait_for(got, timeout_s) else None
