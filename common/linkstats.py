"""Link health of a robot-laptop split, measured on one side (pure; time passed in).

docs/link-driving.md "Saying what the link did". The robot side feeds every command it
receives (:meth:`LinkStats.command`: its arrival time and the stamp of the scan it answers,
both on the robot's run clock, and what the driver did with it); the laptop side feeds the
arrival of anything from the robot (:meth:`LinkStats.heard`). Both call :meth:`tick` on
their schedule. A silence longer than ``outage_ns`` is an outage: :meth:`tick` returns a
``link_lost`` event when it starts, and the next arrival a ``link_restored`` with its length.

The round trip is the command's age when it arrives: robot run time at arrival minus the
stamp of the scan it answers, one clock, no synchronisation — scan to the laptop, the
planner's cycle, the command back.
"""

from __future__ import annotations

import math
from array import array

from schemas.messages import LinkHealth

VERDICTS = ("obeyed", "late", "stale")
MAX_SAMPLES = 100_000      # round trips kept for the percentiles (2.8 h at 10 Hz); then halved


class LinkStats:
    """Counts, round trips and outages of one side of the link (see module doc)."""

    def __init__(self, side: str, outage_ns: int):
        self.side, self.outage_ns = side, outage_ns
        self.rtt_ms = array("f")
        self.counts = dict.fromkeys(VERDICTS, 0)
        self.commands = 0
        self.last_heard: int | None = None
        self.lost_since: int | None = None      # start of the current outage (last arrival)
        self.outages: list[float] = []          # lengths [s] of the finished outages
        self.last_rtt_ms = math.nan

    # -- inputs -----------------------------------------------------------------------------
    def heard(self, now_ns: int) -> list[tuple[str, str]]:
        """Something came from the other side at ``now_ns``; a ``link_restored`` event if
        that ends an outage."""
        out = []
        if self.lost_since is not None:
            length = (now_ns - self.lost_since) * 1e-9
            self.outages.append(length)
            out.append(("link_restored", f"{self.side} side: link back after {length:.2f} s "
                        f"of silence (outage {len(self.outages)})"))
            self.lost_since = None
        self.last_heard = now_ns
        return out

    def command(self, now_ns: int, stamp_ns: int, verdict: str,
                answers_scan: bool = True) -> list[tuple[str, str]]:
        """A command arrived at run time ``now_ns`` answering the scan of ``stamp_ns``
        (``answers_scan`` False: a stop or a teleop command, counted but no round trip)."""
        if verdict not in VERDICTS:
            raise ValueError(f"verdict {verdict!r} is not one of {VERDICTS}")
        self.commands += 1
        self.counts[verdict] += 1
        if not answers_scan:
            return self.heard(now_ns)
        self.last_rtt_ms = (now_ns - stamp_ns) * 1e-6
        if len(self.rtt_ms) >= MAX_SAMPLES:
            self.rtt_ms = self.rtt_ms[::2]
        self.rtt_ms.append(self.last_rtt_ms)
        return self.heard(now_ns)

    def tick(self, now_ns: int) -> list[tuple[str, str]]:
        """A ``link_lost`` event when the silence just passed ``outage_ns``."""
        if (self.lost_since is None and self.last_heard is not None
                and now_ns - self.last_heard > self.outage_ns):
            self.lost_since = self.last_heard
            return [("link_lost", f"{self.side} side: nothing from the other side for "
                     f"{(now_ns - self.last_heard) * 1e-9:.2f} s (limit {self.outage_ns * 1e-9:g} s)")]
        return []

    def reset(self) -> None:
        """A new run: counts, round trips and outages start again."""
        self.__init__(self.side, self.outage_ns)

    # -- outputs ----------------------------------------------------------------------------
    def outage_lengths(self, now_ns: int) -> list[float]:
        """Lengths [s] of every outage, the current one up to ``now_ns`` included."""
        current = [] if self.lost_since is None else [(now_ns - self.lost_since) * 1e-9]
        return [*self.outages, *current]

    def percentile(self, q: float) -> float:
        if not self.rtt_ms:
            return math.nan
        ordered = sorted(self.rtt_ms)
        return float(ordered[min(len(ordered) - 1, int(q / 100.0 * len(ordered)))])

    def report(self, now_ns: int, speed_scale: float = 1.0, monitor_stops: int = 0,
               held_s: float = 0.0) -> LinkHealth:
        lengths = self.outage_lengths(now_ns)
        return LinkHealth(stamp_ns=now_ns, side=self.side,
                          state="up" if self.lost_since is None else "lost",
                          rtt_last_ms=self.last_rtt_ms, rtt_p50_ms=self.percentile(50),
                          rtt_p99_ms=self.percentile(99), commands=self.commands,
                          obeyed=self.counts["obeyed"], late=self.counts["late"],
                          stale=self.counts["stale"], outages=len(lengths),
                          outage_s=sum(lengths), longest_outage_s=max(lengths, default=0.0),
                          speed_scale=speed_scale, monitor_stops=monitor_stops, held_s=held_s)


def summary(health: LinkHealth | None) -> dict | None:
    """The run JSON's ``link`` object from a side's last report (None: no report)."""
    if health is None:
        return None

    def ms(x: float):
        return None if math.isnan(x) else round(x, 1)

    return {"side": health.side, "rtt_p50_ms": ms(health.rtt_p50_ms),
            "rtt_p99_ms": ms(health.rtt_p99_ms), "commands": health.commands,
            "obeyed_commands": health.obeyed, "late_commands": health.late,
            "stale_commands": health.stale, "outages": health.outages,
            "outage_s": round(health.outage_s, 3),
            "longest_outage_s": round(health.longest_outage_s, 3),
            "monitor_stops": health.monitor_stops, "held_s": round(health.held_s, 3),
            "state": health.state}
