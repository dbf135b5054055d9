"""Moving obstacles in the sim: the LiDAR sees them where they are, contact is a collision."""

import math

import numpy as np
import pybullet as p
import pytest

from nodes.lidar_sim.core import LidarParams, LidarSim
from nodes.world_sim.core import WorldCore
from nodes.world_sim.physics import SimBase
from papf.offline.run import simulate
from worlds import parse_world
from worlds.messages import truth_objects

S = 1_000_000_000


def world(track, kind="box"):
    ob = {"kind": kind, "motion": {"track": track}}
    ob.update({"size": [0.4, 0.3]} if kind == "box" else {"radius": 0.2})
    return parse_world({"goal": {"position": [5, 0]}, "obstacles": [ob]})


def test_lidar_sees_a_moving_box_where_its_track_puts_it():
    w = world([[0.0, 3.0, 0.0], [2.0, 1.0, 0.0]])          # 1 m/s towards the robot
    with LidarSim(w, LidarParams(noise_sd=0.0)) as lidar:
        ahead = lidar.params.beams // 2                      # beam at angle 0
        for t_s, x in ((0.0, 3.0), (1.0, 2.0), (1.5, 1.5), (9.0, 1.0)):
            r = lidar.scan(0.0, 0.0, 0.0, int(t_s * S)).ranges[ahead]
            # near face at x - 0.2, sensor 0.02 m ahead of the robot centre
            assert r == pytest.approx(x - 0.2 - 0.02, abs=1e-5)


def test_lidar_sees_the_heading_of_a_box_moving_sideways():
    w = world([[0.0, 2.0, -1.0], [2.0, 2.0, 1.0]])          # heading +y: 0.4 m along y
    with LidarSim(w, LidarParams(noise_sd=0.0, beams=720)) as lidar:
        ranges = lidar.scan(0.0, 0.0, 0.0, 1 * S).ranges        # centre at (2, 0) at t = 1
        hit = np.flatnonzero(np.isfinite(ranges))
        angles = lidar.params.angle_min + hit * lidar.params.angle_increment
        half_width = 2.0 * math.tan(np.max(np.abs(angles)))   # y reach of the hit face
    assert half_width == pytest.approx(0.2, abs=0.02)          # 0.4 m along y, not 0.3


def test_an_obstacle_driving_into_a_standing_robot_is_a_collision():
    w = world([[0.0, 3.0, 0.0], [2.0, 0.0, 0.0]])
    with WorldCore(w, seed=1) as core:
        events = []
        while core.t_ns < 3 * S and not events:
            core.advance()
            events = [m for t, m in core.outputs() if t == "events" and m.kind == "collision"]
    (event,) = events
    # the box's near face (x - 0.2) meets the chassis front (0.1 m) when x = 0.3: t = 1.8 s
    assert event.stamp_ns / S == pytest.approx(1.8, abs=0.03)
    assert "obstacle 0 (box)" in event.detail


def test_sim_scene_follows_the_track_on_sim_time():
    w = world([[1.0, 4.0, 2.0], [3.0, 4.0, 0.0]], kind="cylinder")
    with SimBase(w, seed=0) as sim:
        for _ in range(int(2 * S / sim.params.step_ns)):
            sim.step()
        (x, y, _), _ = p.getBasePositionAndOrientation(sim.obstacles[0], physicsClientId=sim.cid)
    assert (x, y) == pytest.approx((4.0, 1.0), abs=1e-9)       # halfway at t = 2 s


def test_truth_objects_give_pose_velocity_and_size():
    w = world([[0.0, 3.0, 0.0], [2.0, 1.0, 0.0]])
    (tr,) = truth_objects(w, S // 2).tracks
    assert (tr.id, tr.x, tr.y, tr.vx, tr.vy) == pytest.approx((0, 2.5, 0.0, -1.0, 0.0))
    assert (tr.yaw, tr.length, tr.width) == pytest.approx((math.pi, 0.4, 0.3))
    assert truth_objects(w, 0, near=(10.0, 0.0), max_range=5.0).tracks == ()


def test_offline_plan_checks_moving_obstacles_where_they_are():
    # a box drives at 1 m/s down the robot's line towards it: an offline run must see the
    # contact when the box arrives, not against the box's start pose (2.5 m away)
    w = parse_world({"goal": {"position": [3.0, 0.0]}, "obstacles": [
        {"kind": "box", "size": [0.4, 0.3], "motion": {"track": [[0.0, 3.0, 0.0], [3.0, 0.0, 0.0]]}}]})
    r = simulate(w, "apf", seed=0, max_time_s=10.0)
    assert r.outcome == "collision" and 1.0 < r.sim_time_s < 3.0
