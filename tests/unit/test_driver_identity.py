"""The driver's per-step Python, made cheaper, is bit for bit the model it replaced.

The tyre model (nodes/world_sim/physics.py) precomputes its per-wheel constants and the
command gate (common/drive.py) inlines its clamps; both run 25 times per 100 ms
of sim time. Here each runs beside the plain formula (the code before the change, kept
below as the reference) on the same random inputs, and every float must be equal.
"""

from __future__ import annotations

import math
import random

import pybullet as p
import pytest

from common.drive import CommandGate, RosbotLimits
from nodes.world_sim.physics import SimBase, _yaw
from worlds import parse_world


class ReferenceSim(SimBase):
    """SimBase with the tyre model exactly as first written (module doc's formula)."""

    def _apply_tyre_forces(self) -> None:
        cid, robot = self.cid, self.robot
        (px, py, _), quat = p.getBasePositionAndOrientation(robot, physicsClientId=cid)
        (vx, vy, _), (_, _, w) = p.getBaseVelocity(robot, physicsClientId=cid)
        yaw = _yaw(quat)
        c, s = math.cos(yaw), math.sin(yaw)
        vbx, vby = c * vx + s * vy, -s * vx + c * vy
        states = p.getJointStates(robot, self._joints, physicsClientId=cid)
        eps2 = self.params.slip_eps ** 2
        for i in range(4):
            wx, wy = self._wx[i], self._wy[i]
            slip_x = vbx - w * wy - states[i][1] * self._r_eff[i]
            slip_y = vby + w * wx
            k = -self._mu[i] * self._load / math.sqrt(slip_x * slip_x + slip_y * slip_y + eps2)
            fx, fy = k * slip_x, k * slip_y
            p.applyExternalForce(robot, i, [c * fx - s * fy, s * fx + c * fy, 0.0],
                                 [px + c * wx - s * wy, py + s * wx + c * wy, 0.0], p.WORLD_FRAME,
                                 physicsClientId=cid)

    def set_twist(self, v: float, w: float) -> tuple[float, float]:
        prm = self.params
        half = w * prm.effective_track / 2
        lim = prm.wheel_speed_limit
        left = max(-lim, min(lim, (v - half) / prm.wheel_radius))
        right = max(-lim, min(lim, (v + half) / prm.wheel_radius))
        if (left, right) != self._targets:
            p.setJointMotorControlArray(self.robot, self._joints, p.VELOCITY_CONTROL,
                                        targetVelocities=[left, right, left, right],
                                        forces=[prm.motor_torque_limit] * 4, physicsClientId=self.cid)
            self._targets = (left, right)
        return left, right


def reference_gate_output(gate: CommandGate, state: dict, t_ns: int, dt_s: float):
    """CommandGate.output as first written (two _clamp calls, stopped_by_watchdog)."""
    def clamp(x, limit):
        return max(-limit, min(limit, x))
    lim = gate.limits
    stopped = gate.stopped_by_watchdog(t_ns)
    v_t, w_t = (0.0, 0.0) if stopped else gate._target
    v0, w0 = state["out"]
    v = v0 + clamp(v_t - v0, lim.a_max * dt_s)
    w = w0 + clamp(w_t - w0, lim.alpha_max * dt_s)
    state["out"] = (v, w)
    return v, w, stopped


def _world():
    box = {"kind": "box", "center": [0.8, 0.25], "size": [0.4, 0.4]}
    cyl = {"kind": "cylinder", "center": [0.2, -1.0], "radius": 0.3}
    return parse_world({"name": "t", "robot": {"start": [0.0, 0.0, 0.3]}, "goal": {"position": [5.0, 0.0]},
                        "obstacles": [box, cyl]})


def _state(sim: SimBase) -> tuple:
    cid = sim.cid
    pos, quat = p.getBasePositionAndOrientation(sim.robot, physicsClientId=cid)
    lin, ang = p.getBaseVelocity(sim.robot, physicsClientId=cid)
    wheels = tuple(s[:2] + (s[3],) for s in p.getJointStates(sim.robot, sim._joints, physicsClientId=cid))
    return pos, quat, lin, ang, wheels, tuple(sim.contacts())


@pytest.mark.parametrize("seed", [0, 7])
def test_tyre_model_and_twist_are_bit_identical_to_the_formula(seed):
    rng = random.Random(seed)
    touched = False
    with SimBase(_world(), seed=seed) as sim, ReferenceSim(_world(), seed=seed) as ref:
        assert _state(sim) == _state(ref)
        for step in range(1500):
            if step < 250:       # the first second straight into the box: contacts compared too
                v, w = 0.8, 0.0
            elif step % 25 == 0:   # then a new random command every 0.1 s: reverse, turns, stops
                v, w = rng.choice([0.0, rng.uniform(-1.0, 1.0)]), rng.choice([0.0, rng.uniform(-3.0, 3.0)])
            assert sim.set_twist(v, w) == ref.set_twist(v, w)
            sim.step()
            ref.step()
            state = _state(sim)
            assert state == _state(ref), f"step {step}"
            touched = touched or bool(state[-1])
    assert touched


def test_gate_output_is_bit_identical_to_the_clamps():
    rng = random.Random(3)
    gate = CommandGate(RosbotLimits())
    state = {"out": (0.0, 0.0)}
    t = 0
    stops = 0
    for _ in range(20000):
        t += 4_000_000
        if rng.random() < 0.05:   # sparse commands: the watchdog fires between some of them
            gate.command(rng.uniform(-2, 2), rng.uniform(-5, 5), t)
        dt = rng.choice([0.004, 0.002, rng.uniform(1e-4, 0.05)])
        expected = reference_gate_output(gate, state, t, dt)
        got = gate.output(t, dt)
        assert (got.v, got.w, got.stopped_by_watchdog) == expected
        assert math.copysign(1, got.v) == math.copysign(1, expected[0])
        stops += got.stopped_by_watchdog
    assert 0 < stops < 20000
