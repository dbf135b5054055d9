"""Input pairing of the tracker process (pure; no zenoh; wall time injected).

:class:`TrackerLoop` pairs each scan with odometry (lockstep: the same stamp; realtime:
the latest) and gives one ``Objects`` message per tracked scan, stamped with the scan's
stamp. Used by the tracker node (``nodes/tracker/__main__.py``).
"""

from __future__ import annotations

from collections import OrderedDict

from common.units import LOCKSTEP_PAIR_TIMEOUT_S
from nodes.tracker.core import Tracker
from schemas.messages import Odometry, Scan

ODOM_BUFFER = 64          # odometry messages kept for pairing (1.28 s at 50 Hz)


class TrackerLoop:
    """
    - **lockstep** (default): ``scan(t)`` waits for ``odom(t)`` (same stamp); whichever
      arrives second triggers the cycle, so the tracks of instant ``t`` come from the pose of
      instant ``t`` whatever the arrival order. A scan whose odometry has not arrived after
      ``pair_timeout_s`` of wall time is tracked with the newest older pose (or skipped if
      there is none).
    - **realtime**: each scan is tracked with the latest pose.
    """
    def __init__(self, tracker: Tracker, realtime: bool = False, pair_timeout_s: float = LOCKSTEP_PAIR_TIMEOUT_S):
        self.tracker, self.realtime, self.pair_timeout_s = tracker, realtime, pair_timeout_s
        self.odoms: OrderedDict[int, Odometry] = OrderedDict()
        self.pending: list[tuple[Scan, float]] = []
        self.cycles = 0
        self.unpaired = 0

    def on_message(self, topic: str, msg, now: float) -> list:
        """Take one message at ``now`` [s] (odometry kept, a scan paired); the outputs."""
        if topic == "odom" and isinstance(msg, Odometry):
            self.odoms[msg.stamp_ns] = msg
            self.odoms.move_to_end(msg.stamp_ns)
            while len(self.odoms) > ODOM_BUFFER:
                self.odoms.popitem(last=False)
            return [] if self.realtime else self.poll(now)
        if topic == "scan" and isinstance(msg, Scan):
            if self.realtime:
                newest = max(self.odoms.values(), key=lambda o: o.stamp_ns, default=None)
                return self._track(msg, newest)
            self.pending.append((msg, now))
            return self.poll(now)
        return []

    def poll(self, now: float) -> list:
        """Track pending scans that have their pose, or waited longer than the pair timeout."""
        out, keep = [], []
        for scan, arrived in sorted(self.pending, key=lambda p: p[0].stamp_ns):
            t = scan.stamp_ns
            if t in self.odoms:
                out += self._track(scan, self.odoms[t])
            elif now - arrived > self.pair_timeout_s:
                self.unpaired += 1
                older = [o for o in self.odoms.values() if o.stamp_ns <= t]
                out += self._track(scan, max(older, key=lambda o: o.stamp_ns, default=None))
            else:
                keep.append((scan, arrived))
        self.pending = keep
        return out

    def _track(self, scan: Scan, odom: Odometry | None) -> list:
        if odom is None:
            return []
        self.cycles += 1
        return [("objects", self.tracker.update(scan, odom))]
