"""Unit tests of the base driver's pure parts: command gate, ROSbot physics, driver core."""

from __future__ import annotations

import math

import pytest

from common.drive import CommandGate, RosbotLimits
from common.errors import ConfigError
from common.units import period_ns
from nodes.world_sim.core import ContactEpisodes, WorldConfig, WorldCore
from nodes.world_sim.physics import SimBase, SimParams
from schemas.messages import WHEEL_NAMES, Clock, Event, Odometry, Twist, WheelStates
from worlds import load_world, parse_world

S = 1_000_000_000  # ns per s


def world(start=(0.0, 0.0, 0.0), obstacles=()):
    return parse_world({"name": "t", "robot": {"start": list(start)},
                        "goal": {"position": [5.0, 0.0]}, "obstacles": list(obstacles)})


# -- CommandGate -------------------------------------------------------------------
def settle(gate: CommandGate, t_ns: int, seconds: float, dt: float = 0.004):
    out = None
    for i in range(round(seconds / dt)):
        out = gate.output(t_ns + round(i * dt * S), dt)
    return out


def test_gate_clamps_to_rosbot_limits():
    gate = CommandGate(RosbotLimits(watchdog_ns=10 * S))
    gate.command(2.0, -5.0, 0)
    v, w, stopped = settle(gate, 0, 1.0)
    assert (v, w, stopped) == (pytest.approx(0.9), pytest.approx(-3.0), False)


def test_gate_rate_limits_acceleration():
    gate = CommandGate(RosbotLimits())
    gate.command(0.9, 3.0, 0)
    v, w, _ = gate.output(0, 0.1)
    assert v == pytest.approx(0.1) and w == pytest.approx(0.4)   # 1.0 m/s^2, 4.0 rad/s^2
    v, w, _ = gate.output(100_000_000, 0.1)
    assert v == pytest.approx(0.2) and w == pytest.approx(0.8)


def test_gate_after_a_late_step_speeds_up_by_its_cap_and_slows_down_by_the_whole_time():
    gate = CommandGate(RosbotLimits(), speed_up_dt_max_s=0.04)
    gate.command(0.9, 3.0, 0)
    v, w, _ = gate.output(0, 0.3)                  # a loop stalled 300 ms: no jump of speed
    assert (v, w) == (pytest.approx(0.04), pytest.approx(0.16))
    for _ in range(50):
        v, w, _ = gate.output(0, 0.02)
    gate.command(0.0, -3.0, 0)                     # stop; turn the other way
    v, w, _ = gate.output(0, 0.3)                  # braking takes the whole 300 ms
    assert v == pytest.approx(0.9 - 0.3)
    assert w == pytest.approx(3.0 - 1.2)           # 4 rad/s^2 for 300 ms
    gate.command(-0.2, 0.0, 0)
    v, _, _ = gate.output(0, 0.7)
    assert v == pytest.approx(-0.04)               # 0.6 -> 0 by braking, then -0.04 at most


def test_gate_steps_within_the_cap_are_the_uncapped_gate_to_the_bit():
    capped, plain = CommandGate(RosbotLimits(), speed_up_dt_max_s=0.04), CommandGate(RosbotLimits())
    rng = __import__("random").Random(7)
    for k in range(2000):
        if k % 7 == 0:
            v, w = rng.uniform(-1.2, 1.2), rng.uniform(-4, 4)
            capped.command(v, w, k)
            plain.command(v, w, k)
        dt = rng.choice((0.004, 0.02, 0.025, 0.04))
        assert capped.output(k, dt) == plain.output(k, dt)
    with pytest.raises(ConfigError, match="speed_up_dt_max_s"):
        CommandGate(speed_up_dt_max_s=math.nan)


@pytest.mark.parametrize("bad", [(math.nan, 0.5), (0.5, math.inf), (-math.inf, math.nan)])
def test_gate_non_finite_command_is_a_stop(bad):
    gate = CommandGate(RosbotLimits(watchdog_ns=10 * S))
    gate.command(0.5, 1.0, 0)
    assert settle(gate, 0, 1.0)[:2] == (pytest.approx(0.5), pytest.approx(1.0))
    gate.command(*bad, 1 * S)
    v, w, stopped = settle(gate, 1 * S, 0.6)
    assert (v, w, stopped) == (0.0, 0.0, False)
    assert gate.rejected_nonfinite == 1


def test_gate_watchdog_stops_after_half_a_second_without_commands():
    gate = CommandGate()
    assert gate.output(0, 0.004) == (0.0, 0.0, False)        # no command yet: idle, not a stop
    gate.command(0.5, 0.0, 0)
    settle(gate, 0, 0.5)
    assert gate.output(S // 2, 0.004).stopped_by_watchdog is False
    v, _, stopped = gate.output(S // 2 + 1, 0.004)
    assert stopped and v == pytest.approx(0.5 - 0.004)          # decelerates at the limit
    v, w, stopped = settle(gate, S, 1.0)
    assert (v, w, stopped) == (0.0, 0.0, True)
    gate.command(0.1, 0.0, 2 * S)                                # a fresh command re-arms it
    assert gate.output(2 * S, 0.004).stopped_by_watchdog is False


def test_gate_ignores_commands_older_than_the_last():
    gate = CommandGate()
    assert gate.command(0.3, 0.0, 200)
    assert not gate.command(0.9, 0.0, 100)
    assert gate.last_command_ns == 200


@pytest.mark.parametrize("field", ["v_max", "a_max"])
def test_limits_validate(field):
    with pytest.raises(ConfigError, match=field):
        RosbotLimits(**{field: -1.0})
    with pytest.raises(ConfigError, match="watchdog"):
        RosbotLimits(watchdog_ns=0)


# -- SimBase ---------------------------------------------------------------------
def run_twist(sim: SimBase, v: float, w: float, seconds: float) -> list[Odometry]:
    out = []
    for _ in range(round(seconds * S / sim.params.step_ns)):
        sim.set_twist(v, w)
        sim.step()
        out.append(sim.odometry(sim.t_ns))
    return out


def test_sim_drives_straight_at_the_commanded_speed():
    with SimBase(world(), seed=1) as sim:
        odom = run_twist(sim, 0.9, 0.0, 2.0)
    assert odom[-1].v == pytest.approx(0.9, abs=0.02)
    assert odom[-1].x == pytest.approx(1.8, abs=0.1)
    assert abs(odom[-1].y) < 0.05 and abs(odom[-1].w) < 0.05


@pytest.mark.parametrize("yaw0", [0.0, math.pi / 4])
def test_sim_turns_in_place_at_the_commanded_rate_whatever_the_heading(yaw0):
    with SimBase(world(start=(1.0, 2.0, yaw0)), seed=2) as sim:
        odom = run_twist(sim, 0.0, 1.0, 2.0)
        x0, y0 = 1.0, 2.0
    assert odom[-1].w == pytest.approx(1.0, abs=0.05)   # skid steer with the ICR factor
    assert math.hypot(odom[-1].x - x0, odom[-1].y - y0) < 0.05
    assert abs(odom[-1].v) < 0.02


def test_sim_same_seed_is_bit_identical_and_other_seed_differs():
    def trajectory(seed):
        with SimBase(load_world("energy"), seed=seed) as sim:
            return [(o.x, o.y, o.yaw, o.v, o.w) for o in run_twist(sim, 0.6, 0.4, 1.0)]
    a, b, c = trajectory(7), trajectory(7), trajectory(8)
    assert a == b
    assert a != c


def test_sim_wheel_states_report_speed_and_torque():
    with SimBase(world(), seed=0) as sim:
        run_twist(sim, 0.0, 1.0, 0.5)
        ws = sim.wheel_states(sim.t_ns)
    assert isinstance(ws, WheelStates) and ws.names == WHEEL_NAMES
    left, right = ws.speed[0], ws.speed[1]
    assert left < 0 < right and ws.speed[2] == pytest.approx(left, rel=1e-3)
    assert ws.torque[0] < 0 < ws.torque[1]       # skid steering needs torque against scrubbing


def test_sim_detects_collision_with_a_box():
    box = {"kind": "box", "center": [1.0, 0.0], "size": [0.4, 0.4]}
    with SimBase(world(obstacles=[box]), seed=0) as sim:
        assert sim.contacts() == []
        for _ in range(500):
            sim.set_twist(0.5, 0.0)
            sim.step()
            if sim.contacts():
                break
        (contact,) = sim.contacts()
    assert contact.obstacle == 0
    assert contact.x == pytest.approx(0.8, abs=0.02)      # the box's near face
    assert sim.t_ns < 2 * S


def test_sim_rejects_bad_params_and_3d_worlds():
    with pytest.raises(ConfigError, match="mass"):
        SimParams(mass=0.1)
    w3 = parse_world({"goal": {"position": [1.0, 0.0, 1.0]}})
    with pytest.raises(ConfigError, match="3-D"):
        SimBase(w3)


# -- WorldCore ------------------------------------------------------------------
def test_core_publishes_in_protocol_order_on_the_grid():
    with WorldCore(world(), seed=0) as core:
        topics = [t for t, _ in core.outputs()]
        assert topics == ["sim/pose", "odom", "wheels", "clock"]
        core.advance()
        out = dict(core.outputs())
    assert out["clock"] == Clock(stamp_ns=20_000_000)
    assert out["odom"].stamp_ns == out["wheels"].stamp_ns == 20_000_000


def test_core_matches_only_the_answer_to_this_scan():
    with WorldCore(world(), seed=0) as core:
        assert core.is_scan_instant() and core.command(Twist(stamp_ns=0, v=0.1, w=0.0))
        core.advance()
        assert not core.is_scan_instant()
        assert not core.command(Twist(stamp_ns=20_000_000, v=0.1, w=0.0))  # not a scan instant
        for _ in range(4):
            core.advance()
        assert core.t_ns == 100_000_000 and core.last_scan_instant() == 100_000_000
        assert not core.command(Twist(stamp_ns=0, v=0.1, w=0.0))
        assert core.command(Twist(stamp_ns=100_000_000, v=0.1, w=0.0))


def events_of(core: WorldCore) -> list[Event]:
    return [m for t, m in core.outputs() if t == "events"]


def test_core_collision_event_once_per_episode():
    box = {"kind": "box", "center": [1.0, 0.0], "size": [0.4, 0.4]}
    events = []
    with WorldCore(world(obstacles=[box]), seed=0) as core:
        while core.t_ns < 4 * S:
            if core.is_scan_instant():
                core.command(Twist(stamp_ns=core.t_ns, v=0.9, w=0.0))
            events += events_of(core)
            core.advance()
    collisions = [e for e in events if e.kind == "collision"]
    assert len(collisions) == 1                          # pushing on: still one episode
    assert collisions[0].x == pytest.approx(0.8, abs=0.02) and collisions[0].source == "base_driver"
    assert "obstacle 0 (box)" in collisions[0].detail


def test_collision_monitor_debounces():
    mon = ContactEpisodes(gap_ns=100)
    assert mon.update(0, [1]) == [1]
    assert mon.update(50, [1, 2]) == [2]
    assert mon.update(140, [1]) == []           # 90 ns gap: same episode
    assert mon.update(300, [1]) == [1]          # 160 ns gap: a new one


def test_core_watchdog_event_and_stop():
    with WorldCore(world(), seed=0) as core:
        core.command(Twist(stamp_ns=0, v=0.5, w=0.0))
        events = []
        while core.t_ns < 2 * S:
            events += events_of(core)
            core.advance()
        odom = core.sim.odometry(core.t_ns)
    stops = [e for e in events if e.kind == "watchdog_stop"]
    assert len(stops) == 1 and stops[0].stamp_ns == pytest.approx(S // 2, abs=4_000_000)
    assert abs(odom.v) < 0.01


@pytest.mark.parametrize("odom_hz,scan_hz", [(50, 3), (40, 10), (33, 10)])
def test_config_rejects_rates_off_the_grid(odom_hz, scan_hz):
    with pytest.raises(ConfigError):
        WorldConfig.from_rates(odom_hz, scan_hz)


def test_period_ns_exact():
    assert period_ns(10, "scan") == 100_000_000 and period_ns(50, "odom") == 20_000_000
