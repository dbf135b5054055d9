"""The viewer's channels in the Foxglove SDK: one per :data:`nodes.viewer.core.CHANNELS` entry.

JSON encoding with the JSON Schema of each schema name (Foxglove's own for ``foxglove.*``),
in a ``foxglove.Context`` — the live WebSocket server's, or an MCAP writer's for
``papf export foxglove``: the same channels either way.
"""

from __future__ import annotations

import json

import foxglove

from nodes.viewer.core import CHANNELS, schema_json


class FoxgloveChannels:
    def __init__(self, context: foxglove.Context):
        self.context = context
        self.channels: dict[str, foxglove.Channel] = {}
        for spec in CHANNELS:
            schema = foxglove.Schema(name=spec.schema, encoding="jsonschema",
                                     data=json.dumps(schema_json(spec.schema)).encode())
            self.channels[spec.topic] = foxglove.Channel(spec.topic, schema=schema,
                                                         message_encoding="json", context=context)
        self.logged = 0

    def log(self, topic: str, payload: dict, log_time_ns: int) -> None:
        """Encode and log one message, unless nothing listens to its channel."""
        channel = self.channels[topic]
        if not channel.has_sinks():
            return
        channel.log(json.dumps(payload, allow_nan=False, separators=(",", ":")).encode(),
                    log_time=max(int(log_time_ns), 0))
        self.logged += 1

    def log_all(self, outputs) -> None:
        """Log each (topic, payload, log time [ns]) of ``outputs``."""
        for topic, payload, log_time_ns in outputs:
            self.log(topic, payload, log_time_ns)

    def close(self) -> None:
        """Close every channel."""
        for channel in self.channels.values():
            channel.close()
