"""People and other robots as objects: the sim's ground truth (``--objects truth``) from the
driver's ``sim/bodies``, and the tracker on scans with people walking."""

from __future__ import annotations

import math

import pytest

from common import robot
from nodes.world_sim.core import WorldCore
from schemas.messages import Bodies, Twist
from worlds import parse_world
from worlds.messages import truth_objects

S = 1_000_000_000  # ns per s


def crowd_fleet():
    """Two robots facing each other, one box, a person walking across in front of r1."""
    return parse_world({"name": "tp", "robots": [
        {"name": "r1", "start": [0.0, 0.0, 0.0], "goal": [4.0, 0.0]},
        {"name": "r2", "start": [4.0, 0.5, math.pi], "goal": [0.0, 0.5]}],
        "obstacles": [{"kind": "box", "center": [2.0, -2.0], "size": [0.4, 0.4]}],
        "people": [{"start": [2.0, 3.0], "goal": [2.0, -1.0], "speed": 0.8, "radius": 0.25}]})


def test_truth_objects_hold_the_people_and_the_other_robots_of_the_instant():
    world = crowd_fleet()
    with WorldCore(world, seed=0) as core:
        while core.t_ns < S or not core.is_scan_instant():
            if core.is_scan_instant():
                core.command(Twist(stamp_ns=core.t_ns, v=0.0, w=0.0), "r1")
                core.command(Twist(stamp_ns=core.t_ns, v=0.4, w=0.0), "r2")
            core.advance()
        out = dict(core.outputs())
        r2_v = core.sim.velocity(1)
    bodies, pose, people = out["r1/sim/bodies"], out["r1/sim/pose"], out["sim/people"]
    r2 = out["r2/sim/pose"]
    objs = truth_objects(world, core.t_ns, (pose.x, pose.y), 25.0, bodies)
    assert objs.stamp_ns == core.t_ns and objs.source == "truth"
    by_id = {o.id: o for o in objs.tracks}
    assert sorted(by_id) == [0, 1, 3]             # the box, the person (1 + 0), r2 (1 + 1 + 1)
    person = by_id[1]
    assert (person.x, person.y, person.vx, person.vy) == pytest.approx(
        (people.x[0], people.y[0], people.vx[0], people.vy[0]))
    assert people.vy[0] < -0.7                    # walking, at its 0.8 m/s
    assert person.yaw == pytest.approx(math.atan2(people.vy[0], people.vx[0]))
    assert (person.length, person.width) == (0.5, 0.5)
    other = by_id[3]
    assert (other.x, other.y, other.yaw) == pytest.approx((r2.x, r2.y, r2.yaw))
    assert (other.vx, other.vy) == pytest.approx(r2_v) and other.vx < -0.3   # r2 drives at r1
    assert (other.length, other.width) == (robot.BODY_LENGTH_M, robot.BODY_WIDTH_M)
    # r2's own view: r1 is robot 0 of the file -> id 1 + 1 + 0
    mine = truth_objects(world, core.t_ns, None, math.inf, out["r2/sim/bodies"])
    assert {o.id for o in mine.tracks} == {0, 1, 1 + 1 + 0}
    # the range counts for them too: only the person is within 1 m of its own place
    near = truth_objects(world, core.t_ns, (2.0, people.y[0]), 1.0, bodies)
    assert [o.id for o in near.tracks] == [1]


def test_truth_objects_of_bodies_without_velocities_stand_still():
    """A ``Bodies`` recorded before it carried velocities: the bodies are there, at rest."""
    world = crowd_fleet()
    old = Bodies(stamp_ns=0, robots=("r2",), robot_x=(4.0,), robot_y=(0.5,), robot_yaw=(3.0,),
                 person_x=(2.0,), person_y=(3.0,), person_radius=(0.25,))
    tracks = truth_objects(world, 0, bodies=old).tracks
    assert [(o.id, o.vx, o.vy, o.yaw) for o in tracks[1:]] == [(1, 0.0, 0.0, 0.0),
                                                                (3, 0.0, 0.0, 3.0)]
    assert [o.id for o in truth_objects(world, 0).tracks] == [0]   # no bodies: obstacles only


def test_a_fleet_reports_legend_names_each_robot(tmp_path):
    """``papf report`` of a fleet's recording: one run per robot, named in the legend, and
    every robot's start and goal on the trajectory figure (report.csv keeps its columns)."""
    import matplotlib.pyplot as plt

    from nodes.recorder.writer import RunWriter
    from papf.plots.world import draw_world
    from papf.report.figures import label
    from papf.report.report import collect
    from schemas.messages import Event, Odometry

    path = tmp_path / "fleet.mcap"
    with RunWriter(path, {"world": "fleet-corridor-swap", "planner": "apf", "namespace": "r1",
                          "seed": "1"}) as w:
        for ns in ("r1", "r2"):
            w.write_message(f"{ns}/events", Event(stamp_ns=0, kind="run_started", source="t"))
            for k in range(3):
                odom = Odometry(stamp_ns=k * 20_000_000, x=0.01 * k, y=0.0, yaw=0.0, v=0.5, w=0.0)
                w.write_message(f"{ns}/sim/pose", odom)
                w.write_message(f"{ns}/odom", odom)
    runs = collect([path])
    assert [label(r).split(":")[0] for r in runs] == ["r1", "r2"]
    assert label(runs[1]).startswith("r2: apf seed 1 (")
    assert "robot" not in runs[0].row() and runs[0].row()["file"] == "fleet.mcap:r1"
    fig, ax = plt.subplots()
    draw_world(ax, crowd_fleet())
    starts = [ln for ln in ax.lines if ln.get_marker() == "o"]
    assert len(starts) == 2 and [ln.get_label() for ln in starts][0] == "start"
    assert sorted(t.get_text() for t in ax.texts if t.get_text()) == ["r1", "r2"]   # not arrows
    plt.close(fig)


def test_the_tracker_follows_people_walking_past_the_robot():
    """Scans cast with three people walking (1 m/s across, 0.6 m/s towards the robot's
    line, 0.7 m/s diagonally) and a slower robot: one track per person, at its centre
    (not at the visible arc: a quarter of a diameter short before the disc fit) with its
    diameter, and its velocity."""
    from nodes.lidar_sim.core import LidarParams, LidarSim
    from nodes.tracker.core import Tracker
    from schemas.messages import Odometry

    world = parse_world({"name": "e", "robot": {"start": [0, 0, 0]}, "goal": {"position": [5, 0]}})
    people = [((4.0, 2.0), (-1.0, 0.0)), ((5.0, -1.5), (0.0, 0.6)), ((1.0, -3.0), (0.5, 0.5))]
    tracker = Tracker()
    here = Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0)
    worst_pos = worst_vel = 0.0
    with LidarSim(world, LidarParams(), seed=1) as lidar:
        for k in range(41):
            t = k * S // 10
            xy = [(x + vx * t / S, y + vy * t / S) for (x, y), (vx, vy) in people]
            lidar.place_bodies(Bodies(stamp_ns=t, person_x=tuple(p[0] for p in xy),
                                      person_y=tuple(p[1] for p in xy), person_radius=(0.3,) * 3,
                                      robots=("r2",), robot_x=(-2.0 + 0.3 * t / S,),
                                      robot_y=(-1.0,), robot_yaw=(0.0,)))
            tracks = tracker.update(lidar.scan(0.0, 0.0, 0.0, t), here).tracks
            if k < 15:      # 1.5 s for the filter to learn the velocities
                continue
            for (px, py), (_, v) in zip(xy, people, strict=True):
                mine = [o for o in tracks if math.hypot(o.x - px, o.y - py) < 0.3]
                assert len(mine) == 1, f"t = {t / S} s: person at ({px:.2f}, {py:.2f})"
                o = mine[0]
                worst_pos = max(worst_pos, math.hypot(o.x - px, o.y - py))
                worst_vel = max(worst_vel, math.hypot(o.vx - v[0], o.vy - v[1]))
                assert 0.5 < o.length < 0.7 and 0.5 < o.width < 0.7        # 0.6 m across
    assert len(tracks) == 4                                  # the people and the robot
    assert worst_pos < 0.06 and worst_vel < 0.12, (worst_pos, worst_vel)


def test_an_arc_is_a_disc_a_box_corner_or_face_is_not():
    import numpy as np

    from nodes.tracker.box import disc

    rng = np.random.default_rng(0)
    a = np.linspace(math.pi / 2, 3 * math.pi / 2, 9)          # the half facing the sensor
    arc = np.column_stack([3.0 + 0.3 * np.cos(a), 0.3 * np.sin(a)])
    x, y, r = disc(arc + rng.normal(0, 0.005, arc.shape), (0.0, 0.0), 0.6, 0.025)
    assert (x, y, r) == pytest.approx((3.0, 0.0, 0.3), abs=0.03)
    assert disc(arc, (6.0, 0.0), 0.6, 0.025) is None         # seen from behind: hollow
    side = np.linspace(0, 0.5, 7)
    corner = np.concatenate([np.column_stack([2.5 + side[::-1], np.full(7, 0.5)]),
                             np.column_stack([np.full(4, 2.5), np.linspace(0.45, 0.2, 4)])])
    assert disc(corner + rng.normal(0, 0.005, corner.shape), (0.0, 0.0), 0.6, 0.025) is None
    face = np.column_stack([np.full(8, 3.0), np.linspace(-0.25, 0.25, 8)])
    assert disc(face + rng.normal(0, 0.005, face.shape), (0.0, 0.0), 0.6, 0.025) is None
