"""A fleet's odometry tick (nodes.world_sim.core.odom_rate): the scan rate by default, and the drive
the same at either rate — what a planner reads at a scan instant does not depend on it."""

from __future__ import annotations

import math

from common.drive import ODOM_HZ
from nodes.world_sim.core import WorldConfig, WorldCore, odom_rate
from schemas.messages import Twist
from worlds import parse_world

S = 1_000_000_000  # ns per s


ROBOTS = [{"name": "r1", "start": [0, 0], "goal": [3, 0]}, {"name": "r2", "start": [3, 1], "goal": [0, 1]}]


def test_one_robot_ticks_at_50_hz_a_fleet_at_the_scan_rate_and_a_given_rate_wins():
    one, fleet = parse_world({"goal": {"position": [3, 0]}}), parse_world({"robots": ROBOTS})
    crowd = parse_world({"robots": ROBOTS, "people": [{"start": [1, 2], "goal": [1, -2]}]})
    assert odom_rate(one, None, 10.0) == ODOM_HZ == 50.0
    assert odom_rate(fleet, None, 10.0) == 10.0
    assert odom_rate(crowd, None, 10.0) == ODOM_HZ   # people step on the tick
    assert odom_rate(fleet, 50.0, 10.0) == 50.0
    assert odom_rate(one, 25.0, 10.0) == 25.0


def _scan_instants(odom_hz: float, seconds: float) -> list[tuple]:
    """Each robot's odometry at every scan instant of a two-robot swap, both driven by the
    same commands (a function of the instant, answered at every scan as the lockstep does)."""
    world = parse_world({"name": "swap", "robots": [
        {"name": "r1", "start": [0.0, 0.0, 0.0], "goal": [4.0, 0.0]},
        {"name": "r2", "start": [4.0, 0.3, math.pi], "goal": [0.0, 0.3]}]})
    seen = []
    with WorldCore(world, seed=3, config=WorldConfig.from_rates(odom_hz)) as core:
        while core.t_ns <= seconds * S:
            out = core.outputs()
            if core.is_scan_instant():
                t = core.t_ns
                seen.append([(m.stamp_ns, m.x, m.y, m.yaw, m.v, m.w)
                             for topic, m in out if topic.endswith("/odom")])
                for k, name in enumerate(("r1", "r2")):
                    core.command(Twist(stamp_ns=t, v=0.4 + 0.1 * k,
                                       w=0.6 * math.sin(t / S + k)), name)
            core.advance()
    return seen


def test_a_fleet_drives_the_same_at_the_scan_rate_as_at_50_hz_bit_for_bit():
    fast, slow = _scan_instants(50.0, 3.0), _scan_instants(10.0, 3.0)
    assert len(fast) == len(slow) == 31
    assert fast == slow           # every robot's pose and speeds at every scan instant
    assert slow[-1][0][1] > 0.5   # and they did drive
