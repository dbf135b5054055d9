"""The end of a run in a recording: ``run_ended`` and the samples still on their way.

Zenoh orders samples per link only, so ``run_ended`` can reach the recorder before the
nodes' last samples; :class:`RunEndWatch` keeps recording the live keys until each has
delivered the run's last stamp (at most :data:`TAIL_MAX_S`). Used by the recorder node.
"""

from __future__ import annotations

import msgpack

from common.errors import PapfError
from schemas.messages import Event

LIVE_S = 1.0        # [s wall] a key with a sample this recent at run_ended is waited for
TAIL_MAX_S = 2.0    # [s wall] at most spent waiting for the live keys to pass T


def stamp_of(payload: bytes) -> int | None:
    """``stamp_ns`` of one of our messages (msgpack map); None for anything else."""
    try:
        wire = msgpack.unpackb(payload, raw=False)
    except (ValueError, msgpack.ExtraData, msgpack.FormatError, msgpack.StackError):
        return None
    stamp = wire.get("stamp_ns") if isinstance(wire, dict) else None
    return stamp if type(stamp) is int else None


def _reached(stamp: int | None, end_ns: int) -> bool:
    return stamp is None or stamp >= end_ns


class RunEndWatch:
    """Notices the launcher's ``run_ended`` on ``events_key`` and then says when the tail
    is complete. ``arrived(key, payload, now_ns)`` is called for every recorded sample.

    The launcher puts ``run_ended`` (stamp ``T``, the run's last instant) on its own link; the
    samples of ``T`` come from the nodes on theirs, and Zenoh orders samples per link only. So
    ``run_ended`` can reach the recorder before, say, the scan of ``T`` (seen under load: 119 of
    120 scans recorded). :class:`RunEndWatch` therefore does not close at ``run_ended`` but
    opens a tail: every key that was live when ``run_ended`` came (a sample within
    :data:`LIVE_S` of wall time before it) and whose latest sample was stamped before ``T`` is
    recorded until it has delivered a stamp ``>= T``
    (or a payload without one: ROS 2 CDR, foreign data), at most :data:`TAIL_MAX_S` — a node
    that died at the end delivers nothing more, and the file must still close.
    """

    def __init__(self, events_key: str, live_s: float = LIVE_S):
        self.key, self.live_ns = events_key, int(live_s * 1e9)
        self.seen = False              # run_ended has come
        self.end_ns: int | None = None
        self.last: dict[str, tuple[int, bytes]] = {}   # key -> (wall ns, payload) of its latest sample
        self.waiting: set[str] = set()      # live keys without a stamp >= end_ns yet

    def arrived(self, key: str, payload: bytes, now_ns: int) -> None:
        """Note a sample on ``key`` received at ``now_ns`` [ns] (wall), to tell the tail's end."""
        if self.seen:
            if key in self.waiting:
                if _reached(stamp_of(payload), self.end_ns):
                    self.waiting.discard(key)
            return
        self.last[key] = (now_ns, payload)
        if key == self.key:
            self._check(payload, now_ns)

    def _check(self, payload: bytes, now_ns: int) -> None:
        try:
            event = Event.from_bytes(payload)
        except PapfError:  # a bad event is recorded all the same; it ends nothing
            return
        if event.kind == "run_ended":
            self.seen, self.end_ns = True, event.stamp_ns
            self.waiting = {k for k, (t, last) in self.last.items()
                            if k != self.key and now_ns - t <= self.live_ns
                            and not _reached(stamp_of(last), event.stamp_ns)}

    @property
    def complete(self) -> bool:
        """run_ended has come and every live key has passed its stamp."""
        return self.seen and not self.waiting
