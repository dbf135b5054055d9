"""A run's secret: the goal and the planner's status are signed, so each side acts only on
messages of the run that set them up.

The launcher of a run makes a fresh key (:func:`new_key`) and hands it to the processes
it starts through the environment (:data:`ENV`, never on the bus or a command line).
It signs the goal; the planner accepts only goals that verify, and signs its status
messages; the launcher accepts only statuses that verify. A goal put on the bus by
anyone else (another stack, a replay, a hostile peer) is dropped and counted, and so is a
forged ``reached``. A planner started without a key (alone, for tests) accepts any goal.

The tag is HMAC-SHA256 (RFC 2104) over the message's msgpack form without its ``auth``
field, truncated to 128 bits.
"""

from __future__ import annotations

import dataclasses
import hashlib
import hmac
import os
import secrets

import msgpack

ENV = "PAPF_RUN_KEY"          # environment variable that carries the key (hex)
TAG_HEX = 32                  # [hex digits] 128-bit tag


def new_key() -> str:
    """A fresh run key, hex."""
    return secrets.token_hex(16)


def key_from_env(environ=os.environ) -> bytes | None:
    """The run key this process was given, or None."""
    text = environ.get(ENV, "")
    try:
        return bytes.fromhex(text) if text else None
    except ValueError:
        return None


def _tag(msg, key: bytes) -> str:
    wire = {k: v for k, v in msg.to_wire().items() if k != "auth"}
    body = msgpack.packb(wire, use_bin_type=True)
    return hmac.new(key, body, hashlib.sha256).hexdigest()[:TAG_HEX]


def sign(msg, key: bytes | None):
    """``msg`` with its ``auth`` tag set (unchanged without a key)."""
    return msg if key is None else dataclasses.replace(msg, auth=_tag(msg, key))


def verify(msg, key: bytes | None) -> bool:
    """True when ``msg`` carries the tag of ``key`` (always True without a key)."""
    return key is None or hmac.compare_digest(getattr(msg, "auth", ""), _tag(msg, key))
