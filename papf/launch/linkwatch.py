"""The laptop's view of the link to the robot during a run (pure; wall time passed in).

docs/link-driving.md "Saying what the link did". Two sources: the robot's own reports
(``<ns>/link``, :class:`schemas.LinkHealth`: round trips, late commands, outages as the
robot saw them) and the laptop's ear (:class:`common.linkstats.LinkStats` fed with the
arrival of the robot's clock: a silence of :data:`LAPTOP_OUTAGE_S` is an outage here).
It gives the progress line its link text, the run JSON its ``link`` object, and the run's
``reason`` when the link, not the planner, ended the run.
"""

from __future__ import annotations

import math

from common.linkstats import LinkStats, summary
from schemas import LinkHealth

# [s] of silence from the robot the laptop calls an outage: twice the robot's watchdog, so
# a laptop busy for a moment is not a lost link (the robot's own count uses the watchdog)
LAPTOP_OUTAGE_S = 1.0
LATE_SHARE = 0.25       # [-] this share of commands refused by the robot: the link's fault
OUTAGE_SHARE = 0.1      # [-] outages this long a share of the run: the link's fault
BLAMED = ("stagnated", "timeout", "failed")
STALLED = "sim time stuck"   # the launcher's stall reason (papf.launch.sequence): the only failure
                             # the link can cause


class LinkWatch:
    """See the module doc. ``heard`` / ``tick`` take wall time [ns]."""

    def __init__(self):
        self.ear = LinkStats("laptop", int(LAPTOP_OUTAGE_S * 1e9))
        self.robot: LinkHealth | None = None

    def on_health(self, msg: LinkHealth) -> None:
        if msg.side == "robot" and (self.robot is None or msg.stamp_ns >= self.robot.stamp_ns):
            self.robot = msg

    def heard(self, wall_ns: int) -> list[tuple[str, str]]:
        return self.ear.heard(wall_ns)

    def tick(self, wall_ns: int) -> list[tuple[str, str]]:
        return self.ear.tick(wall_ns)

    def text(self) -> str:
        """The progress line's link part, e.g. ``link rtt 586 ms, 3 late``."""
        r = self.robot
        if self.ear.lost_since is not None:
            return "link LOST"
        if r is None or math.isnan(r.rtt_p50_ms):
            return ""
        late = r.late + r.stale
        return (f"link rtt {r.rtt_last_ms:.0f} ms" + (f", {late} late" if late else "")
                + (f", {r.outages} outages" if r.outages else ""))

    def summary(self, wall_ns: int) -> dict:
        """The run JSON's ``link``: the robot's figures, and the outages the laptop saw."""
        out = summary(self.robot) or {"side": "robot", "rtt_p50_ms": None, "rtt_p99_ms": None,
                                      "commands": 0, "late_commands": 0, "outages": 0}
        seen = self.ear.outage_lengths(wall_ns)
        out["laptop_outages"] = len(seen)
        out["laptop_outage_s"] = [round(s, 3) for s in seen]
        return out

    def blame(self, outcome: str, reason: str, wall_ns: int, run_s: float) -> str | None:
        """A ``reason`` naming the link when it, not the planner, ended the run (else None)."""
        if outcome not in BLAMED or (outcome == "failed" and not reason.startswith(STALLED)):
            return None   # a node's death, an interrupt: not the link's to explain
        why = self._fault(wall_ns, run_s)
        if not why:
            return None
        return f"the link: {why} (what the run saw: {reason})" if reason else f"the link: {why}"

    def _fault(self, wall_ns: int, run_s: float) -> str:
        if self.ear.lost_since is not None:
            return (f"nothing from the robot for {(wall_ns - self.ear.lost_since) * 1e-9:.1f} s "
                    "(an outage)")
        r = self.robot
        if r is None:   # a driver that does not report: only what the laptop heard
            return self._laptop_outages(wall_ns, run_s)
        if r.state == "lost":
            return f"the robot heard no command for {r.outage_s:.1f} s in {r.outages} outages"
        refused = r.late + r.stale
        if r.commands and refused / r.commands >= LATE_SHARE:
            return (f"{refused} of {r.commands} commands reached the robot too late to obey "
                    f"(round trip p50 {r.rtt_p50_ms:.0f} ms, p99 {r.rtt_p99_ms:.0f} ms)")
        if run_s > 0 and r.held_s >= LATE_SHARE * run_s:
            return (f"the robot stood {r.held_s:.1f} s of {run_s:.1f} s for want of a command "
                    f"fresh enough to follow (round trip p50 {r.rtt_p50_ms:.0f} ms, "
                    f"p99 {r.rtt_p99_ms:.0f} ms)")
        if r.outages and r.outage_s >= OUTAGE_SHARE * run_s:
            return (f"{r.outages} outages, {r.outage_s:.1f} s without commands "
                    f"(longest {r.longest_outage_s:.1f} s)")
        return self._laptop_outages(wall_ns, run_s)

    def _laptop_outages(self, wall_ns: int, run_s: float) -> str:
        """The outages the laptop itself heard (the robot's report may predate them: it
        comes over the same link)."""
        seen = self.ear.outage_lengths(wall_ns)
        if run_s > 0 and seen and sum(seen) >= OUTAGE_SHARE * run_s:
            return (f"nothing from the robot for {sum(seen):.1f} s of the run in {len(seen)} "
                    f"outage{'s' if len(seen) > 1 else ''} (longest {max(seen):.1f} s)")
        return ""
