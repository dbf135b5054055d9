"""Unit tests of the simulated RPLIDAR A3 core and its scan schedule."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from common.errors import ConfigError
from nodes.lidar_sim.__main__ import ScanSchedule
from nodes.lidar_sim.core import LidarParams, LidarSim
from schemas.messages import Scan
from worlds import parse_world
from worlds.bullet import add_ground, build_world

WALL_AHEAD = {"kind": "box", "center": [3.0, 0.0], "size": [0.4, 2.0]}   # near face at x = 2.8


def world(*obstacles):
    return parse_world({"name": "t", "goal": {"position": [5.0, 0.0]}, "obstacles": list(obstacles)})


def beam(params: LidarParams, angle: float) -> int:
    """Index of the beam closest to ``angle`` [rad] in the sensor frame."""
    return round((angle - params.angle_min) / params.angle_increment) % params.beams


def test_scan_layout_follows_laserscan_conventions():
    prm = LidarParams()
    with LidarSim(world(), prm, seed=0) as lidar:
        scan = lidar.scan(0.0, 0.0, 0.0, 123)
    assert isinstance(scan, Scan) and scan.stamp_ns == 123
    assert scan.ranges.dtype == np.float32 and len(scan.ranges) == 300
    assert scan.angle_min == -math.pi and scan.angle_increment == pytest.approx(2 * math.pi / 300)
    assert (scan.range_min, scan.range_max) == (0.2, 25.0)
    assert scan.sensor_x == prm.sensor_x and Scan.from_bytes(scan.to_bytes()) == scan


def test_no_obstacle_gives_inf_everywhere():
    with LidarSim(world(), seed=1) as lidar:
        assert np.isinf(lidar.scan(0.0, 0.0, 0.3, 0).ranges).all()


def test_box_at_known_distance_within_noise():
    prm = LidarParams(noise_sd=0.01)
    with LidarSim(world(WALL_AHEAD), prm, seed=2) as lidar:
        scan = lidar.scan(0.0, 0.0, 0.0, 500_000_000)
    expected = 2.8 - prm.sensor_x
    ahead = scan.ranges[beam(prm, 0.0)]
    assert abs(ahead - expected) < 5 * prm.noise_sd
    behind = scan.ranges[beam(prm, math.pi)]
    assert math.isinf(behind)
    # beams within +-15 deg all see the wall at expected / cos(angle)
    for a in np.radians([-15, -5, 5, 15]):
        assert scan.ranges[beam(prm, a)] == pytest.approx(expected / math.cos(a), abs=0.05)


def test_pose_and_heading_are_applied():
    prm = LidarParams(noise_sd=0.0)
    side_wall = {"kind": "box", "center": [1.0, 4.0], "size": [2.0, 0.4]}  # near face y = 3.8
    with LidarSim(world(side_wall), prm, seed=0) as lidar:
        scan = lidar.scan(1.0, 0.5, math.pi / 2, 0)                      # facing +y
    assert scan.ranges[beam(prm, 0.0)] == pytest.approx(3.8 - 0.5 - prm.sensor_x, abs=1e-4)


def test_noise_free_is_exact_and_too_close_is_inf():
    prm = LidarParams(noise_sd=0.0)
    close = {"kind": "box", "center": [0.3, 0.0], "size": [0.2, 0.2]}    # face 0.18 m from sensor
    with LidarSim(world(close), prm, seed=0) as lidar:
        scan = lidar.scan(0.0, 0.0, 0.0, 0)
        assert math.isinf(scan.ranges[beam(prm, 0.0)])                    # below range_min
        far = lidar.scan(-0.5, 0.0, 0.0, 0)
    assert far.ranges[beam(prm, 0.0)] == pytest.approx(0.7 - prm.sensor_x, abs=1e-5)


def test_noise_is_deterministic_per_seed_and_stamp():
    def ranges(seed, stamp):
        with LidarSim(world(WALL_AHEAD), seed=seed) as lidar:
            return lidar.scan(0.1, -0.2, 0.05, stamp).ranges
    a = ranges(4, 700_000_000)
    assert np.array_equal(a, ranges(4, 700_000_000))
    assert not np.array_equal(a, ranges(4, 800_000_000))
    assert not np.array_equal(a, ranges(5, 700_000_000))


def test_noise_sigma_matches_setting():
    prm = LidarParams(noise_sd=0.02, beams=2000)
    boxes = [{"kind": "box", "center": [3.0 * math.cos(a), 3.0 * math.sin(a)], "size": [0.3, 0.3],
              "yaw": a} for a in np.linspace(0, 2 * math.pi, 40, endpoint=False)]
    with LidarSim(world(*boxes), prm, seed=9) as lidar:
        clean = lidar.true_ranges(0.0, 0.0, 0.0)
        noisy = lidar.scan(0.0, 0.0, 0.0, 0).ranges
    hit = np.isfinite(clean) & np.isfinite(noisy)
    assert hit.sum() > 100
    assert np.std(noisy[hit] - clean[hit]) == pytest.approx(0.02, rel=0.25)


@pytest.mark.parametrize("kwargs", [{"beams": 0}, {"range_min": 30.0}, {"noise_sd": -1.0},
                                    {"height": 0.0}])
def test_params_validate(kwargs):
    with pytest.raises(ConfigError):
        LidarParams(**kwargs)


def test_schedule_publishes_once_per_period_and_restarts():
    sch = ScanSchedule(100)
    assert [t for t in (0, 20, 40, 80, 100, 120, 200) if sch.due(t)] == [0, 100, 200]
    assert [t for t in (250, 290, 310, 330) if sch.due(t)] == [310]  # off-grid stamps
    assert sch.due(0)                                                  # clock went back: new run


def test_build_world_places_every_shape():
    w = parse_world({"goal": {"position": [1.0, 0.0]}, "obstacles": [
        {"kind": "box", "center": [1.0, 2.0], "size": [0.4, 0.2], "height": 0.3},
        {"kind": "wall", "from": [0.0, -1.0], "to": [2.0, -1.0], "thickness": 0.1},
        {"kind": "cylinder", "center": [-1.0, 0.5], "radius": 0.25},
    ]})
    cid = p.connect(p.DIRECT)
    try:
        ground = add_ground(cid)
        bodies = build_world(cid, w)
        assert len(bodies) == 3 and ground not in bodies
        aabbs = [np.array(p.getAABB(b, physicsClientId=cid)) for b in bodies]
    finally:
        p.disconnect(cid)
    margin = 0.02   # Bullet pads AABBs by a collision margin
    np.testing.assert_allclose(aabbs[0], [[0.8, 1.9, 0.0], [1.2, 2.1, 0.3]], atol=margin)
    np.testing.assert_allclose(aabbs[1], [[0.0, -1.05, 0.0], [2.0, -0.95, 0.5]], atol=margin)
    np.testing.assert_allclose(aabbs[2], [[-1.25, 0.25, 0.0], [-0.75, 0.75, 0.5]], atol=margin)


def test_cast_equals_the_plain_per_beam_reference():
    """true_ranges builds its rays and reads the hits with array and C-level maps; the
    result must be the straightforward per-beam cast's, bit for bit (hits and misses)."""
    lidar = LidarSim(world(WALL_AHEAD, {"kind": "cylinder", "center": [-1.0, 1.5], "radius": 0.3}),
                     LidarParams(noise_sd=0.0), seed=0)
    prm, rng = lidar.params, np.random.default_rng(5)
    for _ in range(40):
        x, y, yaw = rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-4, 4)
        c, s = math.cos(yaw), math.sin(yaw)
        ox, oy = x + c * prm.sensor_x - s * prm.sensor_y, y + s * prm.sensor_x + c * prm.sensor_y
        d = lidar._angles + yaw
        origin = np.empty((prm.beams, 3))
        origin[:] = (ox, oy, prm.height)
        end = origin.copy()
        end[:, 0] += prm.range_max * np.cos(d)
        end[:, 1] += prm.range_max * np.sin(d)
        hits = p.rayTestBatch(origin.tolist(), end.tolist(), physicsClientId=lidar.cid)
        ref = np.array([h[2] if h[0] >= 0 else np.inf for h in hits]) * prm.range_max
        got = lidar.true_ranges(x, y, yaw)
        assert np.isfinite(got).any() and np.isinf(got).any()
        assert got.tobytes() == ref.tobytes()
    lidar.close()
