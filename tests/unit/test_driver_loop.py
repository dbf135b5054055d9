"""The simulated driver's lockstep / real-time schedule (nodes.world_sim.loop), in-process:
a fake core and wall time passed in — no processes, no sleeping."""

from __future__ import annotations

import pytest

from nodes.world_sim.loop import WorldLoop
from schemas.messages import Clock, Event, Twist

PERIOD_NS = 20_000_000      # 50 Hz odometry
SCAN_EVERY = 5              # 10 Hz scans


class FakeCore:
    """The WorldCore interface the loop uses: one clock message per instant."""

    def __init__(self):
        self.t_ns, self.commands = 0, []

    def is_scan_instant(self) -> bool:
        return self.t_ns % (SCAN_EVERY * PERIOD_NS) == 0

    def outputs(self):
        return [("clock", Clock(stamp_ns=self.t_ns))]

    def command(self, twist: Twist) -> bool:
        self.commands.append(twist.stamp_ns)
        return twist.stamp_ns == self.t_ns and self.is_scan_instant()

    def advance(self) -> None:
        self.t_ns += PERIOD_NS


def cmd(stamp_ns: int) -> Twist:
    return Twist(stamp_ns=stamp_ns, v=0.1, w=0.0)


def run_until(loop: WorldLoop, now: float):
    """Step as the wrapper does with an empty inbox, until the loop waits beyond ``now``."""
    out = []
    while True:
        more, until = loop.step(now)
        out += more
        if until is None or until > now:
            return out, until


def clocks(out) -> list[int]:
    return [m.stamp_ns for topic, m in out if topic == "clock"]


def test_lockstep_waits_for_the_command_of_each_scan():
    core = FakeCore()
    loop = WorldLoop(core, realtime=False, lockstep_timeout_s=2.0, now=100.0)
    out, until = loop.step(100.0)
    assert clocks(out) == [0] and until == 102.0 and not loop.ready   # scan at t=0: wait
    out, until = loop.step(101.9)                   # still nothing: keep waiting, publish nothing
    assert out == [] and until == 102.0
    loop.on_message("cmd_vel", cmd(12345))          # answers no scan
    assert not loop.ready
    loop.on_message("cmd_vel", cmd(0))
    assert loop.ready
    out, until = loop.step(101.9)   # 20, 40, 60, 80 ms and the scan at 100 ms: one burst
    assert clocks(out) == [k * PERIOD_NS for k in range(1, SCAN_EVERY + 1)]
    assert until == pytest.approx(103.9) and not loop.ready and loop.faults == 0
    loop.on_message("cmd_vel", cmd(5 * PERIOD_NS))
    out, until = loop.step(102.0)
    assert clocks(out) == [k * PERIOD_NS for k in range(6, 2 * SCAN_EVERY + 1)]


def test_a_missing_command_is_a_fault_then_real_time_until_a_command_answers_again():
    core = FakeCore()
    loop = WorldLoop(core, realtime=False, lockstep_timeout_s=2.0, now=0.0)
    loop.step(0.0)
    out, until = run_until(loop, 2.5)               # the wait is over: fault, free running
    faults = [m for t, m in out if t == "events" and m.kind == "node_fault"]
    assert len(faults) == 1 and faults[0].stamp_ns == 0 and loop.free_running
    assert until == pytest.approx(2.5 + PERIOD_NS / 1e9)   # paced: t = 20 ms at wall0 + 0.02 s
    out, _ = run_until(loop, 2.5 + 0.1 + 1e-9)     # 100 ms later: up to the next scan instant
    assert clocks(out)[-1] == 5 * PERIOD_NS
    loop.on_message("cmd_vel", cmd(5 * PERIOD_NS))  # answers the latest scan: lockstep again
    assert not loop.free_running


def test_realtime_never_waits_for_commands_and_run_ended_stops():
    core = FakeCore()
    loop = WorldLoop(core, realtime=True, lockstep_timeout_s=2.0, now=10.0)
    out, until = loop.step(10.0)
    assert clocks(out) == [0] and until == 10.0     # scan instant, but nothing to wait for
    out, until = loop.step(10.0)
    assert out == [] and until == pytest.approx(10.02)
    out, until = run_until(loop, 11.0)              # a second of wall time: 50 more instants
    assert clocks(out) == [k * PERIOD_NS for k in range(1, 51)] and loop.faults == 0
    loop.on_message("events", Event(stamp_ns=0, kind="run_ended", source="launcher", detail=""))
    assert loop.ready and loop.step(12.0) == ([], None)
