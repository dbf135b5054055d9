"""The world simulator's schedule around a :class:`~nodes.world_sim.core.WorldCore`:
lockstep or real time, pure — no zenoh, wall time passed in (docs/architecture.md, "Lockstep").

Per sim instant ``t`` (the core's odometry grid):

1. free running only: wait until the wall clock reaches ``wall0 + t``;
2. publish the core's outputs of ``t`` (clock, pose, odometry, wheels, events) — in
   lockstep those of every instant up to the next scan instant together, at that instant;
3. at a scan instant in lockstep: wait until a ``cmd_vel`` answers the scan of ``t``
   (its ``stamp_ns == t``), at most ``lockstep_timeout_s`` of wall time. None came: a
   ``node_fault`` event and free running in real time, until a command answers the latest
   scan again (then back to lockstep). Otherwise: take whatever is queued, without waiting;
4. advance the core one instant.

A fleet's core (``[[robots]]``) takes each robot's ``<name>/cmd_vel`` and says an instant
is answered only when every robot's command for it came (``WorldCore.command``).

``run_ended`` on ``events`` ends the run. The process wrapper
(``nodes/world_sim/__main__.py``) only wires this to the bus::

    out, until = loop.step(now)    # publish out; then feed messages until `until`
    ...                            # (or until loop.ready) with loop.on_message(...)
"""

from __future__ import annotations

from common.units import NS_PER_S
from schemas.messages import Event, Twist

SOURCE = "base_driver"   # the core's SOURCE (not imported: the core pulls in pybullet)
LOCKSTEP_FAULT = "no cmd_vel with stamp_ns="   # how a lockstep timeout's node_fault begins

PACE, AWAIT, DRAIN = "pace", "await", "drain"


class WorldLoop:
    def __init__(self, core, realtime: bool, lockstep_timeout_s: float, now: float, log=None):
        self.core, self.realtime, self.timeout_s, self.log = core, realtime, lockstep_timeout_s, log
        self.free_running = realtime       # True: pace to the wall clock, do not wait
        self.wall0 = now                   # wall time of sim t = 0 while free running [s]
        self.ended = False
        self.matched = False               # a command answering the scan of this instant came
        self.last_scan_ns = -1             # latest scan instant published [ns]
        self.phase = PACE
        self.deadline = now                # [s wall] end of the lockstep wait (AWAIT)
        self.faults = 0

    @property
    def ready(self) -> bool:
        """True when waiting for input is over before the deadline (a command answered)."""
        return self.ended or (self.phase == AWAIT and self.matched)

    def on_message(self, topic: str | None, msg) -> None:
        if topic is None:   # a stop request's wake-up
            return
        if (topic == "cmd_vel" or topic.endswith("/cmd_vel")) and isinstance(msg, Twist):
            robot = topic[:-len("/cmd_vel")]   # a fleet's "<name>/cmd_vel"; "" for one robot
            self.matched |= self.core.command(msg, robot) if robot else self.core.command(msg)
            if self.free_running and not self.realtime and msg.stamp_ns == self.last_scan_ns:
                if self.log:
                    self.log.info("cmd_vel answers scan %d ns again: back to lockstep", msg.stamp_ns)
                self.free_running = False
        elif topic.endswith("events") and isinstance(msg, Event) and msg.kind == "run_ended":
            self.ended = True

    def step(self, now: float) -> tuple[list[tuple[str, object]], float | None]:
        """Go as far as wall time ``now`` allows: (messages to publish, wall time [s] until
        which to feed inputs before the next call; a past one = only what is queued).
        ``None``: the run has ended."""
        out: list[tuple[str, object]] = []
        while not self.ended:
            if self.phase == PACE:
                due = self.wall0 + self.core.t_ns / NS_PER_S
                if self.free_running and now < due:
                    return out, due
                out += self._emit(now)
                if self.phase == DRAIN and self.free_running:
                    return out, now
                # lockstep: the instants up to the next scan go out together (one burst per
                # cycle: one write and one wake for each reader, not five); what is queued
                # meanwhile is taken while waiting for that scan's command
            elif self.phase == AWAIT and not self.matched:
                if now < self.deadline:
                    return out, self.deadline
                out.append(self._fault(now))
                self._advance()
            else:              # DRAIN after its inputs were taken, or AWAIT answered
                self._advance()
        return out, None

    def _emit(self, now: float) -> list[tuple[str, object]]:
        core = self.core
        self.matched = False
        out = core.outputs()
        if core.is_scan_instant():
            self.last_scan_ns = core.t_ns
        if core.is_scan_instant() and not self.free_running:
            self.phase, self.deadline = AWAIT, now + self.timeout_s
        else:
            self.phase = DRAIN
        return out

    def _advance(self) -> None:
        self.core.advance()
        self.phase = PACE

    def _fault(self, now: float) -> tuple[str, Event]:
        t = self.core.t_ns
        detail = (f"{LOCKSTEP_FAULT}{t} within {self.timeout_s:g} s (wall); "
                  "free running in real time until a command answers the latest scan")
        if self.log:
            self.log.warning("lockstep: %s", detail)
        self.faults += 1
        self.free_running = True
        self.wall0 = now - t / NS_PER_S
        return "events", Event(stamp_ns=t, kind="node_fault", source=SOURCE, detail=detail)
