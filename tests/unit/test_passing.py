"""The passing layer (nodes/planner/passing.py): the planner's command untouched without a
neighbour, keep-right and ORCA with one, a fleet's run with it, the launcher's wiring."""

import math

import numpy as np
import pytest

from nodes.planner.field import APFParams
from nodes.planner.passing import Passing, PassingParams
from nodes.planner.registry import make_planner
from nodes.planner.road import Track
from schemas.messages import Goal, Odometry, Scan

APF = APFParams()
ON = Passing(PassingParams(mode="orca"))


def robot(x, y, yaw=0.0, v=0.0):
    """Another ROSbot as the obstacle tracks carry it (chassis box, velocity)."""
    return Track(x, y, yaw, v * math.cos(yaw), v * math.sin(yaw), 0.2, 0.235)


def test_no_neighbour_in_range_leaves_the_command_untouched():
    cmd = (0.0712, -0.31)
    for tracks in ((), (robot(3.5, 0.0),), (robot(-2.0, -2.5),)):
        assert ON.adjust(0.0, 0.0, 0.0, 0.1, 0.0, 0.1, *cmd, tracks, APF) == cmd
    off = Passing(PassingParams(mode="off"))
    assert off.adjust(0.0, 0.0, 0.0, 0.1, 0.0, 0.1, *cmd, (robot(0.5, 0.0, math.pi, 0.1),), APF) == cmd


def test_head_on_both_keep_right_and_stay_apart():
    """Two robots driving at each other turn to their own right, so they pass left side to
    left side; a velocity that would reach the other within the time horizon is not taken."""
    me, other = (0.0, 0.0, 0.0), (1.2, 0.0, math.pi)
    v1, w1 = ON.adjust(*me, 0.1, 0.0, 0.1, 0.1, 0.0, (robot(*other, v=0.1),), APF)
    v2, w2 = ON.adjust(*other, 0.1, math.pi, 0.1, 0.1, 0.0, (robot(*me, v=0.1),), APF)
    assert w1 < 0 and w2 < 0                     # both turn clockwise: to their right
    assert 0 <= v1 <= APF.v_max and 0 <= v2 <= APF.v_max


def test_nobody_ahead_means_no_turn_to_the_right():
    """A robot behind, going the same way, changes nothing of the heading asked."""
    v, w = ON.adjust(0.0, 0.0, 0.0, 0.1, 0.0, 0.1, 0.1, 0.0, (robot(-1.0, 0.0, 0.0, 0.1),), APF)
    assert w == pytest.approx(0.0, abs=1e-9) and v == pytest.approx(0.1, abs=1e-6)


def test_a_robot_in_the_way_slows_or_steers_the_command():
    """A robot standing 0.5 m ahead: the command no longer drives straight into it."""
    v, w = ON.adjust(0.0, 0.0, 0.0, 0.1, 0.0, 0.1, 0.1, 0.0, (robot(0.5, 0.0),), APF)
    assert w != 0.0 or v < 0.1


def test_the_planner_core_applies_the_layer_only_with_tracks():
    """One cycle of the planner core: the layer changes the command only when tracks are
    near; without it (one robot) the command is the planner's, bit for bit."""
    scan = Scan(stamp_ns=0, angle_min=-math.pi, angle_increment=2 * math.pi / 360, range_min=0.1,
                range_max=10.0, ranges=np.full(360, np.inf, np.float32))
    odom = Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.1, w=0.0)
    plain, layered = make_planner("papf"), make_planner("papf")
    layered.passing = ON
    for p in (plain, layered):
        p.set_goal(Goal(stamp_ns=0, x=5.0, y=0.0))
    assert plain.step(scan, odom)[0] == layered.step(scan, odom)[0]
    layered.set_objects([robot(0.8, 0.0, math.pi, 0.1)])
    assert layered.step(scan, odom)[0] != plain.step(scan, odom)[0]


def test_a_wall_or_a_car_is_no_agent():
    """A long track (a wall of the truth objects, a road's car) is left to the planner: only
    robots, people and small obstacles are ORCA's neighbours."""
    wall = Track(1.5, 1.0, 0.0, 0.0, 0.0, 5.0, 0.05)
    person = Track(1.0, -0.5, 0.0, 0.0, 0.0, 0.6, 0.6)
    assert ON.neighbours(0.0, 0.0, (wall, person, robot(0.5, 0.5))) == [robot(0.5, 0.5), person]
    cmd = (0.0712, -0.31)
    assert ON.adjust(0.0, 0.0, 0.0, 0.1, 0.0, 0.1, *cmd, (wall,), APF) == cmd


def _planner_argv(world, *extra):
    from papf.launch.profile import LaunchOptions, load_profile, resolve

    opt = LaunchOptions("sim", values={"world": world, "planner": "papf", **dict(extra)})
    return {p.name: p.argv for p in resolve(load_profile("sim"), opt).processes
            if p.name.endswith("planner") or p.name.endswith("lidar_sim")}


def test_a_fleet_passes_by_default_one_robot_never_unless_asked():
    fleet = _planner_argv("fleet-swap")
    assert all("--passing" in a and "--objects" in a for n, a in fleet.items() if n.endswith("planner"))
    assert all("--truth-objects" in a for n, a in fleet.items() if n.endswith("lidar_sim"))
    off = _planner_argv("fleet-swap", ("passing", "off"))
    assert not any("--passing" in a or "--objects" in a for a in off.values())
    one = _planner_argv("energy")
    assert not any("--passing" in a or "--objects" in a for a in one.values())
    asked = _planner_argv("energy", ("passing", "orca"))
    assert "--passing" in asked["planner"] and "--objects" in asked["planner"]


def test_passing_without_tracks_is_refused_before_anything_starts():
    from common.errors import ConfigError

    with pytest.raises(ConfigError, match="--passing orca needs"):
        _planner_argv("fleet-swap", ("objects", "none"))


def test_offline_head_on_swap_passes_wider_with_the_layer():
    """papf plan of fleet-swap (two robots exactly head-on): both reach without a contact
    either way; with the layer they keep well apart (keep right, ORCA), alone they brush."""
    from papf.offline.run import simulate

    runs = {m: simulate("fleet-swap", "papf", max_time_s=90, passing=m).crowd["robots"]
            for m in ("off", "orca")}
    for robots in runs.values():
        assert [r["outcome"] for r in robots] == ["reached", "reached"]
        assert sum(r["collisions"] for r in robots) == 0
    sep = {m: min(r["min_robot_separation_m"] for r in robots) for m, robots in runs.items()}
    assert sep["orca"] > 0.5 > sep["off"]
