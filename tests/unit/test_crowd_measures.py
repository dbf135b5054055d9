"""common/crowd_measures.py: hand-made geometry with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.crowd_measures import CrowdMeter, box_box_distance, box_corners, point_box_distance
from common.robot import BODY_LENGTH_M, BODY_WIDTH_M

L2, W2 = BODY_LENGTH_M / 2, BODY_WIDTH_M / 2


def test_point_to_an_oriented_box():
    # a robot at (1, 2) facing +y: its length lies along y, its width along x
    d = point_box_distance(np.array([[1.0, 2.0 + L2 + 0.3], [1.0 + W2 + 0.4, 2.0],
                                     [1.0 + W2 + 0.3, 2.0 + L2 + 0.4], [1.0, 2.0]]),
                           1.0, 2.0, math.pi / 2)
    np.testing.assert_allclose(d, [0.3, 0.4, 0.5, 0.0], atol=1e-12)


def test_box_to_box():
    assert box_box_distance((0, 0, 0), (BODY_LENGTH_M + 0.25, 0, 0)) == pytest.approx(0.25)
    # turned 90 degrees: the other's half-width now lies along x
    assert box_box_distance((0, 0, 0), (L2 + W2 + 0.1, 0, math.pi / 2)) == pytest.approx(0.1)
    assert box_box_distance((0, 0, 0), (0.05, 0.02, 0.7)) == 0.0
    # a plus sign of two long-ish boxes overlapping with no corner inside the other: still 0
    assert box_box_distance((0, 0, 0), (0, 0, math.pi / 2)) == 0.0
    # corner to corner across a diagonal
    c = box_corners(0, 0, 0)[2]
    d = box_box_distance((0, 0, 0), (2 * c[0] + 0.3, 2 * c[1] + 0.4, 0))
    assert d == pytest.approx(0.5)


def test_min_separation_discomfort_and_intrusions():
    meter = CrowdMeter()
    r = 0.3
    # a person passes the robot's left side at gaps 1.0, 0.4, 0.1, 0.4, 1.0, 0.3 m (0.5 s steps)
    for k, gap in enumerate([1.0, 0.4, 0.1, 0.4, 1.0, 0.3]):
        meter.update(0.5 * k, {"r1": (0.0, 0.0, 0.0)},
                     np.array([[0.0, W2 + r + gap]]), np.array([r]))
    m = meter.results()["r1"]
    assert m.min_person_separation_m == pytest.approx(0.1)
    assert m.min_separation_m == pytest.approx(0.1)
    assert math.isinf(m.min_robot_separation_m)
    assert m.discomfort_s == pytest.approx(0.5)      # the one step that ended at 0.1 m
    assert m.intrusions == 2                          # entered at 0.4, and again at 0.3
    assert m.path_m == 0.0 and m.irregularity_rad_per_m == 0.0


def test_robots_see_each_other():
    meter = CrowdMeter()
    meter.update(0.0, {"a": (0, 0, 0), "b": (BODY_LENGTH_M + 0.7, 0, 0)}, np.zeros((0, 2)),
                 np.zeros(0))
    res = meter.results()
    assert res["a"].min_robot_separation_m == pytest.approx(0.7)
    assert res["b"].min_separation_m == pytest.approx(0.7)
    assert res["a"].intrusions == 0 and math.isinf(res["a"].min_person_separation_m)


def test_path_irregularity():
    # straight to the goal: no unnecessary turning, although it first turned 90 degrees to it
    meter = CrowdMeter(goals={"r": (0.0, 2.0)})
    for k, pose in enumerate([(0, 0, 0), (0, 0, math.pi / 2), (0, 1, math.pi / 2),
                              (0, 2, math.pi / 2)]):
        meter.update(float(k), {"r": pose}, np.zeros((0, 2)), np.zeros(0))
    m = meter.results()["r"]
    assert m.rotation_rad == pytest.approx(math.pi / 2)
    assert m.irregularity_rad_per_m == pytest.approx(0.0)
    # a zigzag over 2 m: 0.5 rad out and 0.5 rad back, none of it needed: 1 rad per 2 m
    meter = CrowdMeter(goals={"r": (2.0, 0.0)})
    for k, pose in enumerate([(0, 0, 0), (1, 0, 0.5), (1, 0, 0), (2, 0, 0.0)]):
        meter.update(float(k), {"r": pose}, np.zeros((0, 2)), np.zeros(0))
    assert meter.results()["r"].irregularity_rad_per_m == pytest.approx(1.0 / 2.0)


def test_bad_inputs():
    meter = CrowdMeter()
    meter.update(1.0, {"r": (0, 0, 0)}, np.zeros((0, 2)), np.zeros(0))
    with pytest.raises(ValueError, match="time"):
        meter.update(0.5, {"r": (0, 0, 0)}, np.zeros((0, 2)), np.zeros(0))
    with pytest.raises(ValueError, match="radii"):
        meter.update(2.0, {"r": (0, 0, 0)}, np.zeros((2, 2)), np.zeros(1))


def test_robot_separation_is_every_pairs_minimum_to_the_bit():
    """The meter computes a pair once and skips pairs too far apart to matter: each robot's
    minimum is still that of every pair, both ways, to the bit (random fleets, many steps)."""
    rng = np.random.default_rng(3)
    names = [f"r{i}" for i in range(12)]
    meter = CrowdMeter()
    naive = dict.fromkeys(names, math.inf)
    grid = np.array([(i % 4, i // 4) for i in range(len(names))], float) * 1.0
    seen = set()
    for step in range(60):   # robots on a 1 m grid, jostling more and more: minima fall
        xy = grid + rng.uniform(-1, 1, (len(names), 2)) * (0.05 + 0.6 * step / 60)
        yaw = rng.uniform(-math.pi, math.pi, len(names))
        robots = {n: (float(x), float(y), float(a))
                  for n, (x, y), a in zip(names, xy, yaw, strict=True)}
        meter.update(step * 0.1, robots, np.zeros((0, 2)), np.zeros(0))
        for n, pose in robots.items():
            for m, other in robots.items():
                if m != n:
                    naive[n] = min(naive[n], box_box_distance(pose, other))
        got = meter.results()
        assert {n: got[n].min_robot_separation_m for n in names} == naive
        seen |= set(naive.values())
    assert len(seen) > 30 and min(seen) == 0.0   # many minima, and contacts too
