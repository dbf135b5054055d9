"""Energy meter: battery pack, the two power models, pairing/determinism, and the node process."""

from __future__ import annotations

import math
import queue
import random
import sys

import numpy as np
import pytest

from common.errors import ConfigError
from common.transport import wait_alive
from nodes.energy_meter import models as M
from nodes.energy_meter.battery import (
    CELL_OCV_SOC,
    CELL_OCV_V,
    Battery,
    EnergyError,
    PackParams,
    cell_ocv,
    solve_current,
)
from nodes.energy_meter.core import EnergyMeter
from schemas import BatteryState, BatteryVoltage, Keys, Odometry, Twist, WheelStates

DT_NS = 20_000_000   # 50 Hz, as the sim driver publishes


def odom(t_ns: int, v: float = 0.0, w: float = 0.0) -> Odometry:
    return Odometry(stamp_ns=t_ns, x=0.0, y=0.0, yaw=0.0, v=v, w=w)


def wheels(t_ns: int, speed=(0.0,) * 4, torque=(0.0,) * 4) -> WheelStates:
    return WheelStates(stamp_ns=t_ns, speed=tuple(speed), torque=tuple(torque))


# -- battery ----------------------------------------------------------------------------------
def test_ocv_table_is_monotone_and_hits_documented_points():
    assert np.all(np.diff(CELL_OCV_SOC) > 0) and np.all(np.diff(CELL_OCV_V) > 0)
    socs = np.linspace(-0.1, 1.1, 241)
    assert np.all(np.diff([cell_ocv(s) for s in socs]) >= 0)
    assert cell_ocv(0.0) == 3.0 and cell_ocv(1.0) == 4.2 and cell_ocv(0.5) == 3.74
    assert cell_ocv(1.5) == 4.2 and cell_ocv(-1.0) == 3.0          # clamped
    assert cell_ocv(0.55) == pytest.approx(0.5 * (3.74 + 3.82))     # linear between points
    assert Battery().ocv() == pytest.approx(12.6)                   # 3S, full
    assert Battery(PackParams(initial_soc=0.5)).ocv() == pytest.approx(3 * 3.74)


def test_ocv_is_numpy_interp_bit_for_bit():
    """cell_ocv runs in plain floats (50 Hz in the meter) but must stay numpy.interp exactly:
    random SoCs, every knot and its neighbours, the clamped ends and a run near full."""
    rng = np.random.default_rng(7)
    knots = [float(np.nextafter(k, d)) for k in CELL_OCV_SOC for d in (-2.0, 2.0)]
    socs = [*rng.uniform(-0.2, 1.2, 20000), *CELL_OCV_SOC, *knots,
            *(1.0 - k * 3.3e-7 for k in range(3000))]
    for soc in map(float, socs):
        ref = float(np.interp(min(max(soc, 0.0), 1.0), CELL_OCV_SOC, CELL_OCV_V))
        assert cell_ocv(soc) == ref, soc
    assert math.isnan(cell_ocv(math.nan))


def test_current_solves_the_voltage_sag_quadratic():
    current, over = solve_current(10.0, 12.6, 0.24)
    assert not over
    assert (12.6 - current * 0.24) * current == pytest.approx(10.0, rel=1e-12)
    assert current == pytest.approx((12.6 - math.sqrt(12.6**2 - 4 * 0.24 * 10.0)) / 0.48)
    assert solve_current(10.0, 12.5, 0.0) == (10.0 / 12.5, False)
    assert solve_current(0.0, 12.6, 0.24) == (0.0, False)
    current, over = solve_current(1000.0, 12.6, 0.24)     # above OCV^2 / 4R = 165 W
    assert over and current == pytest.approx(12.6 / 0.48)


def test_constant_power_integrates_to_hand_computed_charge():
    power, total_s, dt = 12.0, 10.0, 0.02
    pack = Battery()
    first = pack.draw(power, dt)
    r = 3 * 0.080
    i0 = (12.6 - math.sqrt(12.6**2 - 4 * r * power)) / (2 * r)
    assert first.current_A == pytest.approx(i0, rel=1e-12)
    assert first.voltage_V == pytest.approx(12.6 - i0 * r, rel=1e-12)
    assert pack.charge_used_mAh == pytest.approx(i0 * dt / 3.6, rel=1e-12)
    for _ in range(int(total_s / dt) - 1):
        pack.draw(power, dt)
    v = 12.6 - i0 * r     # SoC moves < 0.1 % in 10 s: the voltage stays ~the first step's
    assert pack.charge_used_mAh == pytest.approx(power * total_s / v / 3.6, rel=2e-3)
    assert pack.energy_J == pytest.approx(power * total_s, rel=1e-9)
    assert pack.soc == pytest.approx(1.0 - pack.charge_used_mAh / 3500.0, rel=1e-12)


def test_measured_voltage_replaces_the_model_voltage():
    pack = Battery()
    d = pack.draw(11.0, 1.0, measured_voltage_V=11.0)
    assert d.current_A == 1.0 and d.voltage_V == 11.0
    assert pack.charge_used_mAh == pytest.approx(1000.0 / 3600.0)


def test_pack_settings_are_checked():
    with pytest.raises(ConfigError, match="initial_soc"):
        PackParams(initial_soc=1.5)
    with pytest.raises(EnergyError, match="not finite"):
        Battery().draw(float("nan"), 0.1)


# -- paper model (eq. 6) ---------------------------------------------------------------------
def test_paper_constant_speed_is_viscous_plus_b_plus_ps():
    model, p = M.PaperModel(), M.PaperParams()
    model.update(odom(0, v=0.3))
    power = model.update(odom(DT_NS, v=0.3))
    viscous = 2 * p.f_v_Nm / p.wheel_radius_m * 0.3
    assert model.terms["m_v_a"] == 0.0 and model.terms["I_w_beta"] == 0.0
    assert model.terms["viscous"] == pytest.approx(viscous)
    assert power == pytest.approx(viscous + M.B_W + M.P_S_W)


def test_paper_acceleration_terms_are_m_v_a_and_i_w_beta():
    model, p = M.PaperModel(), M.PaperParams()
    model.update(odom(0, v=0.2, w=0.5))
    model.update(odom(DT_NS, v=0.22, w=0.6))     # a = 1 m/s^2, beta = 5 rad/s^2
    assert model.terms["m_v_a"] == pytest.approx(M.MASS_KG * 0.21 * 1.0)      # midpoint v
    assert model.terms["I_w_beta"] == pytest.approx(p.yaw_inertia_kgm2 * 0.55 * 5.0)
    assert p.yaw_inertia_kgm2 == pytest.approx(2.84 * (0.2**2 + 0.235**2) / 12)


def test_paper_no_regeneration_on_braking_and_reverse_uses_abs_speed():
    model = M.PaperModel()
    model.update(odom(0, v=-0.4))
    power = model.update(odom(DT_NS, v=-0.2))      # slowing down in reverse
    assert model.terms["m_v_a"] == 0.0
    assert model.terms["viscous"] == pytest.approx(2 * M.F_V_NM / M.WHEEL_RADIUS_M * 0.3)
    assert power > M.P_S_W
    regen = M.PaperModel(M.PaperParams(regeneration=True))
    regen.update(odom(0, v=0.4))
    regen.update(odom(DT_NS, v=0.2))
    assert regen.terms["m_v_a"] == pytest.approx(M.MASS_KG * (0.2**2 - 0.4**2) / 2 / 0.02)


def test_paper_idle_draws_only_ps():
    model = M.PaperModel()
    model.update(odom(0))
    assert model.update(odom(DT_NS)) == M.P_S_W
    always_b = M.PaperModel(M.PaperParams(b_while_moving_only=False))
    assert always_b.update(odom(0)) == M.P_S_W + M.B_W


# -- motor model ------------------------------------------------------------------------------
def test_wheel_power_is_tau_omega_plus_copper_loss():
    p = M.MotorParams(gear_efficiency=1.0, no_load_current_A=0.0)
    tau_w, omega_w = 0.05, 5.0
    tau_m, omega_m = tau_w / M.GEAR_RATIO, omega_w * M.GEAR_RATIO
    expected = tau_m * omega_m + (tau_m / M.TORQUE_CONSTANT_NM_A) ** 2 * M.WINDING_RESISTANCE_OHM
    assert M.wheel_power(tau_w, omega_w, p) == pytest.approx(expected, rel=1e-12)
    assert M.wheel_power(0.0, 0.0, p) == 0.0
    stall = M.wheel_power(0.3, 0.0, p)                               # holding: copper loss only
    assert stall == pytest.approx((0.3 / M.GEAR_RATIO / M.TORQUE_CONSTANT_NM_A) ** 2 * 2.1)


def test_wheel_power_with_gearbox_and_no_load_losses():
    p = M.MotorParams()
    tau_m = 0.05 / (M.GEAR_RATIO * M.GEAR_EFFICIENCY)
    omega_m = 5.0 * M.GEAR_RATIO
    expected = (tau_m * omega_m + (tau_m / M.TORQUE_CONSTANT_NM_A) ** 2 * 2.1
                + M.TORQUE_CONSTANT_NM_A * M.NO_LOAD_CURRENT_A * omega_m)
    assert M.wheel_power(0.05, 5.0, p) == pytest.approx(expected, rel=1e-12)


def test_braking_wheel_is_clamped_unless_regeneration():
    assert M.wheel_power(-0.3, 20.0, M.MotorParams()) == 0.0
    regen = M.MotorParams(regeneration=True, no_load_current_A=0.0)
    tau_m = -0.3 * M.GEAR_EFFICIENCY / M.GEAR_RATIO
    expected = tau_m * 20.0 * M.GEAR_RATIO + (tau_m / M.TORQUE_CONSTANT_NM_A) ** 2 * 2.1
    assert expected < 0 and M.wheel_power(-0.3, 20.0, regen) == pytest.approx(expected)


def test_motor_model_sums_wheels_trapezoid_plus_ps():
    model, p = M.MotorModel(), M.MotorParams()
    w0, w1 = wheels(0, (4.0,) * 4, (0.02,) * 4), wheels(DT_NS, (6.0,) * 4, (0.04,) * 4)
    assert model.update(None, w0) == pytest.approx(4 * M.wheel_power(0.02, 4.0, p) + M.P_S_W)
    mean = 2 * (M.wheel_power(0.02, 4.0, p) + M.wheel_power(0.04, 6.0, p))
    assert model.update(None, w1) == pytest.approx(mean + M.P_S_W)
    with pytest.raises(EnergyError, match="speeds"):
        model.update(None, WheelStates(stamp_ns=2 * DT_NS, speed=(1.0,), torque=(1.0, 2.0)))


def test_settings_override_and_unknown_names_are_listed():
    model = M.make_model("motor", {"p_s_W": "8.5", "regeneration": "true"})
    assert model.params.p_s_W == 8.5 and model.params.regeneration is True
    with pytest.raises(ConfigError, match="valid: .*p_s_W"):
        M.make_model("paper", {"nope": 1})
    with pytest.raises(ConfigError, match="not one of"):
        EnergyMeter("magic")
    with pytest.raises(ConfigError, match="'bogus'.*valid: cells_series.*p_s_W"):
        EnergyMeter("motor", {"bogus": 1})
    with pytest.raises(ConfigError, match="number"):
        EnergyMeter("paper", {"f_v_Nm": "abc"})
    assert EnergyMeter("paper", {"initial_soc": "0.5"}).battery.soc == 0.5


# -- meter: pairing and determinism -----------------------------------------------------------
def drive_sequence(n: int = 150) -> tuple[list[Odometry], list[WheelStates]]:
    """A start, cruise, turn and stop profile with wheel torques."""
    odoms, wheel_msgs = [], []
    for k in range(n):
        t = k * DT_NS
        v = min(0.02 * k, 0.5) if k < 100 else max(0.5 - 0.05 * (k - 100), 0.0)
        w = 0.8 if 60 <= k < 80 else 0.0
        ws = v / M.WHEEL_RADIUS_M
        left, right = ws - w * 0.096 / M.WHEEL_RADIUS_M, ws + w * 0.096 / M.WHEEL_RADIUS_M
        tau = 0.05 if k < 25 else (-0.05 if k >= 100 else 0.01)
        odoms.append(odom(t, v, w))
        wheel_msgs.append(wheels(t, (left, right, left, right), (tau, tau, tau, tau)))
    return odoms, wheel_msgs


def interleave(odoms, wheel_msgs, rng: random.Random | None):
    """Merge the two streams, each kept in order; random interleaving when rng is given."""
    out, i, j = [], 0, 0
    while i < len(odoms) or j < len(wheel_msgs):
        coin = rng.random() < 0.5 if rng else True
        take_odom = j >= len(wheel_msgs) or (i < len(odoms) and coin)
        if take_odom:
            out.append(odoms[i])
            i += 1
        else:
            out.append(wheel_msgs[j])
            j += 1
    return out


def meter_all(model: str, msgs) -> list[BatteryState]:
    meter = EnergyMeter(model)
    return [s for s in (meter.feed(m) for m in msgs) if s is not None]


@pytest.mark.parametrize("model", ["motor", "paper"])
def test_pairs_in_any_arrival_order_give_identical_results(model):
    odoms, wheel_msgs = drive_sequence()
    reference = meter_all(model, [m for pair in zip(odoms, wheel_msgs, strict=True) for m in pair])
    assert [s.stamp_ns for s in reference] == [o.stamp_ns for o in odoms]
    expected = [s.to_bytes() for s in reference]
    orders = [interleave(odoms, wheel_msgs, None),          # one stream 150 messages ahead
              [m for pair in zip(wheel_msgs, odoms, strict=True) for m in pair]]
    orders += [interleave(odoms, wheel_msgs, random.Random(seed)) for seed in range(5)]
    for msgs in orders:
        assert [s.to_bytes() for s in meter_all(model, msgs)] == expected


@pytest.mark.parametrize("model", ["motor", "paper"])
def test_same_sequence_gives_bit_identical_states_and_charge_grows(model):
    msgs = interleave(*drive_sequence(), random.Random(7))
    a, b = meter_all(model, msgs), meter_all(model, msgs)
    assert [s.to_bytes() for s in a] == [s.to_bytes() for s in b]
    assert a[0].charge_used_mAh == 0.0 and a[0].model == model
    charges = [s.charge_used_mAh for s in a]
    assert all(y > x for x, y in zip(charges, charges[1:], strict=False))
    assert a[-1].energy_J == pytest.approx(math.fsum(s.power * 0.02 for s in a[1:]), rel=1e-9)


def test_lost_and_stale_messages_are_skipped():
    meter = EnergyMeter("paper")
    assert meter.feed(odom(0)) is None
    assert meter.feed(wheels(0)).stamp_ns == 0
    assert meter.feed(odom(DT_NS)) is None                # its wheels never come
    meter.feed(odom(2 * DT_NS))
    state = meter.feed(wheels(2 * DT_NS))
    assert state.stamp_ns == 2 * DT_NS and meter.discarded == 1
    assert state.charge_used_mAh == pytest.approx(state.current * 0.04 / 3.6)   # spans the gap
    assert meter.feed(wheels(DT_NS)) is None and meter.stale == 1
    with pytest.raises(EnergyError, match="Twist"):
        meter.feed(Twist(stamp_ns=0, v=0.0, w=0.0))


def test_measured_voltage_hook():
    meter = EnergyMeter("paper")
    meter.set_measured_voltage(11.5, 0)
    meter.feed(odom(0))
    state = meter.feed(wheels(0))
    assert state.voltage == 11.5 and state.current == pytest.approx(M.P_S_W / 11.5)
    with pytest.raises(EnergyError, match="measured voltage"):
        meter.set_measured_voltage(-1.0, 0)


# -- the node as a process ---------------------------------------------------------------------
@pytest.mark.e2e
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
