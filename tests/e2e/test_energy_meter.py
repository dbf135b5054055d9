"""The energy meter node process: meters over a router and survives garbage."""

from __future__ import annotations

import queue
import sys

from common.transport import wait_alive
from schemas import BatteryState, BatteryVoltage, Keys, Odometry, WheelStates

DT_NS = 20_000_000   # 50 Hz, as the sim driver publishes


def odom(t_ns: int, v: float = 0.0, w: float = 0.0) -> Odometry:
    return Odometry(stamp_ns=t_ns, x=0.0, y=0.0, yaw=0.0, v=v, w=w)


def wheels(t_ns: int, speed=(0.0,) * 4, torque=(0.0,) * 4) -> WheelStates:
    return WheelStates(stamp_ns=t_ns, speed=tuple(speed), torque=tuple(torque))


# -- the node as a process ---------------------------------------------------------------------
def test_node_process_meters_and_survives_garbage(router, session, spawn):
    keys = Keys("emtest")
    got: queue.Queue = queue.Queue()
    sub = session.declare_subscriber(
        keys.battery, lambda s: got.put(BatteryState.from_bytes(s.payload.to_bytes())))
    child = spawn("energy_meter", [sys.executable, "-m", "nodes.energy_meter", "--model", "motor",
                                   "--connect", router, "--namespace", keys.ns])
    try:
        assert not wait_alive(session, keys, ["energy_meter"], timeout_s=30,
                              abort=lambda: child.returncode is not None), list(child.tail)
        states = []
        for k in range(6):
            t = k * DT_NS
            if k == 3:   # garbage on both inputs must be dropped, not crash the node
                session.put(keys.battery_measured,   # a voltage it cannot use: counted, dropped
                            BatteryVoltage(stamp_ns=t, voltage=-1.0).to_bytes())
                session.put(keys.odom, b"\xc1 not msgpack")
                session.put(keys.wheels, wheels(t).to_bytes()[:-3])
                session.put(keys.wheels, odom(t).to_bytes())
            session.put(keys.odom, odom(t, v=0.2).to_bytes())
            session.put(keys.wheels, wheels(t, (4.7,) * 4, (0.01,) * 4).to_bytes())
            states.append(got.get(timeout=15))
        assert [s.stamp_ns for s in states] == [k * DT_NS for k in range(6)]
        charges = [s.charge_used_mAh for s in states]
        assert charges[0] == 0.0 and all(y > x for x, y in zip(charges, charges[1:], strict=False))
        assert all(s.model == "motor" and 9.0 < s.voltage < 12.7 for s in states)
        assert child.returncode is None
    finally:
        sub.undeclare()


def test_one_process_meters_each_robot_of_a_fleet_as_its_own_meter(router, session, spawn):
    """``--robots r1,r2``: each robot's token, its own account on its own namespace, the
    states a meter of its own computes from the same messages (the core, fed alike)."""
    from nodes.energy_meter.core import EnergyMeter

    names = ["fm1", "fm2"]
    got: dict[str, queue.Queue] = {n: queue.Queue() for n in names}
    subs = [session.declare_subscriber(Keys(n).battery, lambda s, q=got[n]: q.put(
        BatteryState.from_bytes(s.payload.to_bytes()))) for n in names]
    child = spawn("energy_meter", [sys.executable, "-m", "nodes.energy_meter", "--model", "motor",
                                   "--connect", router, "--namespace", "fmproc",
                                   "--robots", ",".join(names)])
    try:
        for ns in (*names, "fmproc"):
            assert not wait_alive(session, Keys(ns), ["energy_meter"], timeout_s=30,
                                  abort=lambda: child.returncode is not None), list(child.tail)
        expected = {n: EnergyMeter("motor") for n in names}
        for k in range(5):
            t = k * DT_NS
            for i, n in enumerate(names):   # different work per robot: different accounts
                o, w = odom(t, v=0.1 * (i + 1)), wheels(t, (2.0 * (i + 1),) * 4, (0.02 * (i + 1),) * 4)
                session.put(Keys(n).odom, o.to_bytes())
                session.put(Keys(n).wheels, w.to_bytes())
                expected[n].feed(o)
                want = expected[n].feed(w)
                assert got[n].get(timeout=15) == want
        assert got["fm1"].empty() and got["fm2"].empty()
        assert child.returncode is None
    finally:
        for sub in subs:
            sub.undeclare()
