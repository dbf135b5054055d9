"""The seal on every sample a keyed process puts: who may say it, which run, and that it is new.

A process started by a launcher holds the run's key (:mod:`common.runauth`, given through the
environment) and the run's id (:data:`RUN_ID_ENV`). Everything it puts on the bus carries a
*seal* in the sample's Zenoh attachment (the payload is unchanged, so recordings, ``papf
topic echo`` and the ROS 2 tools see the same bytes)::

    b"PS1" | sender (4 bytes) | seq (8, big-endian) | run id (8) | tag (16)   = 39 bytes

- ``sender``: random per sealing process (a publisher's identity for the ordering below);
- ``seq``: the sender's wall clock in ns at sealing, strictly increasing per sender (so a
  restarted process goes on above its predecessor without any state kept);
- ``run id``: 8 random bytes the launcher chose for this run (:func:`new_run_id`); zeros =
  no run (``papf teleop`` between runs);
- ``tag``: HMAC-SHA256 (RFC 2104) with the key over ``"PS1" | key expression | 0 | sender |
  seq | run id | payload``, cut to 128 bits. The key expression is in it, so a sealed goal
  put again on another key is no goal.

A receiver with the key (:class:`Opener`) accepts a sample only when the tag verifies, its
``seq`` is above the last one accepted from that sender on that key (a replay — the same
bytes put again, however captured — is dropped and counted), and its run id is the run the
receiver serves. Without a key a process seals nothing and checks nothing (a node started
alone, for tests: docs/architecture.md "Trust").
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import time
from collections import OrderedDict

MAGIC = b"PS1"
SENDER_LEN, SEQ_LEN, RUN_LEN, TAG_LEN = 4, 8, 8, 16
SEAL_LEN = len(MAGIC) + SENDER_LEN + SEQ_LEN + RUN_LEN + TAG_LEN
NO_RUN = bytes(RUN_LEN)             # the run id of a sample sealed outside any run
RUN_ID_ENV = "PAPF_RUN_ID"          # the run id a launcher gives its processes (hex)
SENDERS_KEPT = 4096                 # [-] (key, sender) pairs whose last seq is remembered

# verdicts of Opener.check
OK, UNSIGNED, FORGED, REPLAY, OTHER_RUN = "ok", "unsigned", "forged", "replay", "other_run"
# a run's receiver (common.intake.Trust) tells OTHER_RUN apart: sealed outside any run
# (NO_RUN), its sender had not joined the run yet (a robot-side node's odometry still on the
# link when the run began). Refused all the same
BEFORE_RUN = "before_run"
# a follower (the robot side, common.intake.Trust) tells OTHER_RUN apart too: a command of a
# run it has not seen begin, the new run's first command, which overtook its run_started on
# another connection of a jittered link. Refused all the same
AHEAD_OF_RUN = "ahead_of_run"


def new_run_id() -> str:
    """A fresh run id, hex (16 digits)."""
    return secrets.token_hex(RUN_LEN)


def run_bytes(run_id: str | bytes | None) -> bytes:
    """A run id as its 8 bytes (hex text or bytes; None or "" = :data:`NO_RUN`); ValueError
    for anything else."""
    if run_id is None or run_id in ("", b""):
        return NO_RUN
    raw = bytes.fromhex(run_id) if isinstance(run_id, str) else bytes(run_id)
    if len(raw) != RUN_LEN:
        raise ValueError(f"a run id is {RUN_LEN} bytes ({2 * RUN_LEN} hex digits), not {len(raw)}")
    return raw


def run_from_env(environ=os.environ) -> bytes | None:
    """The run id this process was given (:data:`RUN_ID_ENV`), or None."""
    try:
        return run_bytes(environ.get(RUN_ID_ENV)) if environ.get(RUN_ID_ENV) else None
    except ValueError:
        return None


def _tag(key: bytes, key_expr: str, head: bytes, payload: bytes) -> bytes:
    mac = hmac.new(key, MAGIC + key_expr.encode() + b"\0" + head, hashlib.sha256)
    mac.update(payload)
    return mac.digest()[:TAG_LEN]


class Sealer:
    """Seals what one process puts (module doc). ``run`` may change (a driver that starts a
    new run, a LiDAR that follows its driver's run)."""

    def __init__(self, key: bytes, run: bytes | None = None, clock=time.time_ns):
        self.key, self.run = key, run or NO_RUN
        self.sender = secrets.token_bytes(SENDER_LEN)
        self._clock, self._last = clock, 0

    def seal(self, key_expr: str, payload: bytes) -> bytes:
        """The attachment of ``payload`` put on ``key_expr``."""
        seq = max(self._clock(), self._last + 1)
        self._last = seq
        head = self.sender + seq.to_bytes(SEQ_LEN, "big") + self.run
        return MAGIC + head + _tag(self.key, key_expr, head, payload)


def parse(attachment: bytes | None) -> tuple[bytes, int, bytes, bytes] | None:
    """``(sender, seq, run, tag)`` of a seal, or None when ``attachment`` is not one."""
    if attachment is None or len(attachment) != SEAL_LEN or not attachment.startswith(MAGIC):
        return None
    i = len(MAGIC)
    sender = attachment[i:i + SENDER_LEN]
    i += SENDER_LEN
    seq = int.from_bytes(attachment[i:i + SEQ_LEN], "big")
    i += SEQ_LEN
    return sender, seq, attachment[i:i + RUN_LEN], attachment[i + RUN_LEN:]


class Opener:
    """A receiver's check of seals: :meth:`check` -> ``(verdict, run id or None)``.

    ``run``: the run this receiver serves; samples of another run are :data:`OTHER_RUN`
    (``None``: any run, e.g. a robot-side node between runs). The last ``seq`` of each
    (key, sender) is kept (at most :data:`SENDERS_KEPT` pairs: a keyless peer cannot add any).
    """

    def __init__(self, key: bytes, run: bytes | None = None):
        self.key, self.run = key, run
        self._last: OrderedDict[tuple[str, bytes], int] = OrderedDict()

    def check(self, key_expr: str, payload: bytes, attachment: bytes | None,
              run: bytes | None = None) -> tuple[str, bytes | None]:
        """The verdict on one received sample; ``run`` overrides the receiver's run for this
        check (a driver accepting a new run's ``run_started``)."""
        seal = parse(attachment)
        if seal is None:
            return UNSIGNED, None
        sender, seq, run_id, tag = seal
        head = attachment[len(MAGIC):len(MAGIC) + SENDER_LEN + SEQ_LEN + RUN_LEN]
        if not hmac.compare_digest(tag, _tag(self.key, key_expr, head, payload)):
            return FORGED, None
        stream = (key_expr, sender)
        if seq <= self._last.get(stream, -1):
            return REPLAY, run_id
        expected = self.run if run is None else run
        if expected is not None and run_id != expected:
            return OTHER_RUN, run_id
        self._last[stream] = seq
        self._last.move_to_end(stream)
        while len(self._last) > SENDERS_KEPT:
            self._last.popitem(last=False)
        return OK, run_id


def seq_age_s(attachment: bytes | None, now_ns: int | None = None) -> float | None:
    """How old a seal is by the receiver's wall clock [s] (negative: from the future), or None."""
    seal = parse(attachment)
    if seal is None:
        return None
    return ((time.time_ns() if now_ns is None else now_ns) - seal[1]) / 1e9
