"""Offline planning (papf.offline.run.simulate and its motion models), random worlds, plots:
fast, no processes."""

import json
import math

import matplotlib.image as mpimg
import numpy as np
import pytest

from common.errors import ConfigError
from common.optional import tomllib
from nodes.planner.registry import PLANNERS
from papf.offline.point3d import cast_points, fibonacci_directions
from papf.offline.result import write_path
from papf.offline.run import simulate
from papf.offline.unicycle import FootprintChecker
from papf.offline.world_gen import (
    GAP_RANGE_M,
    KINDS,
    ROBOT_RADIUS_M,
    bottleneck_width,
    generate,
    generate_solvable,
    is_solvable,
    world_to_toml,
)
from papf.plots.paths import plot_paths
from worlds import load_world, parse_world
from worlds.geometry import signed_distance

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def corridor(obstacles, goal=(3.0, 0.0), start=(0.0, 0.0, 0.0)):
    """A 1.6 m-wide walled corridor from x = -0.6 to 3.6 plus ``obstacles``."""
    walls = [{"kind": "wall", "from": [-0.6, y], "to": [3.6, y], "thickness": 0.1} for y in (-0.8, 0.8)]
    walls += [{"kind": "wall", "from": [x, -0.8], "to": [x, 0.8], "thickness": 0.1} for x in (-0.6, 3.6)]
    return parse_world({"name": "corridor", "robot": {"start": list(start)},
                        "goal": {"position": list(goal)}, "obstacles": walls + obstacles})


# -- 2-D closed loop ------------------------------------------------------------------
def test_apf_reaches_the_goal_in_the_open_world():
    r = simulate("open", "apf")
    assert r.outcome == "reached" and r.collisions == 0
    assert np.hypot(*(r.path[-1] - np.array(load_world("open").goal))) <= 0.1 + 0.01
    assert 4.9 <= r.length_m <= 5.2          # 5 m straight ahead, minus the tolerance
    assert r.duration_s > 0 and r.sim_time_s >= r.duration_s
    assert r.path.shape[1] == 2 and r.times.shape[0] == r.path.shape[0] == r.headings.shape[0]


def test_apf_stagnates_in_a_dead_end_and_does_not_hang():
    r = simulate("papf-test-4", "apf", max_time_s=200)
    assert r.outcome == "stagnated"
    assert "no progress" in r.reason or r.reason
    assert r.sim_time_s < 200 and r.collisions == 0


@pytest.mark.skipif("papf" not in PLANNERS, reason="PAPF strategy not registered yet")
def test_papf_escapes_the_dead_end():
    r = simulate("papf-test-4", "papf", max_time_s=200)
    assert r.outcome == "reached" and r.collisions == 0 and r.min_clearance_m > 0


def test_collision_is_detected_and_ends_the_run():
    # no setting switches avoidance off (safety floors), so a panel moving across the whole
    # corridor at 3 m/s runs into the robot, whatever it does
    world = corridor([{"kind": "box", "size": [0.2, 1.5],
                       "motion": {"track": [[0.0, 2.0, 0.0], [1.0, -1.0, 0.0]]}}])
    r = simulate(world, "apf")
    assert r.outcome == "collision" and r.collisions == 1
    assert r.min_clearance_m < 0
    assert r.sim_time_s < 1.5                   # the run ended at the collision


def test_timeout_when_the_time_limit_is_short():
    r = simulate("open", "apf", max_time_s=2.0)
    assert r.outcome == "timeout" and math.isclose(r.sim_time_s, 2.0)


def test_same_seed_same_path_and_bad_dt_rejected():
    a, b = simulate("papf-test-1", "apf", max_time_s=10), simulate("papf-test-1", "apf", max_time_s=10)
    np.testing.assert_array_equal(a.path, b.path)
    with pytest.raises(ConfigError, match="dt"):
        simulate("open", "apf", dt=0.0)


def test_footprint_clearance_of_the_chassis_box():
    # wall face at x = 0.45; the chassis reaches 0.100 m ahead (0.200 m long) -> 0.35 m
    world = parse_world({"goal": {"position": [1, 0]}, "obstacles": [
        {"kind": "box", "center": [0.5, 0.0], "size": [0.1, 1.0]}]})
    chk = FootprintChecker(world)
    try:
        assert chk.clearance(0.0, 0.0, 0.0) == pytest.approx(0.35, abs=1e-3)
        # turned 90 deg the chassis reaches 0.1175 m ahead
        assert chk.clearance(0.0, 0.0, math.pi / 2) == pytest.approx(0.45 - 0.1175, abs=1e-3)
        assert chk.clearance(0.4, 0.0, 0.0) < 0
    finally:
        chk.close()


def test_path_files_csv_and_json(tmp_path):
    r = simulate("open", "apf", max_time_s=3.0)
    write_path(r, tmp_path / "p.csv")
    lines = (tmp_path / "p.csv").read_text().splitlines()
    assert lines[0] == "t,x,y,yaw" and len(lines) == r.path.shape[0] + 1
    write_path(r, tmp_path / "p.json")
    doc = json.loads((tmp_path / "p.json").read_text())
    assert doc["outcome"] == "timeout" and doc["columns"] == ["t", "x", "y"]
    assert len(doc["path"]) == r.path.shape[0]
    with pytest.raises(ConfigError, match="suffix"):
        write_path(r, tmp_path / "p.txt")


# -- the one entry point picks the motion model ------------------------------------
def test_simulate_picks_the_motion_model_from_the_world_and_motion():
    assert simulate("open", "apf", max_time_s=1.0).motion == "unicycle"
    car = simulate("iapf-case-a", "iapf", max_time_s=1.0)
    assert car.motion == "car" and car.cycles == 50 and car.trace.times[-1] == car.sim_time_s
    whole = simulate("iapf-case-a", "iapf", max_time_s=1.0, whole_time=True)
    assert whole.outcome == "timeout" and whole.reason == "ran the whole 1 s"
    assert simulate("wang-table1-fig5", "wang-apf", motion="fixed-step").motion == "fixed-step"
    with pytest.raises(ConfigError, match="car-scale"):
        simulate("open", "apf", whole_time=True)


# -- 3-D point robot ---------------------------------------------------------------
def test_3d_point_robot_reaches_and_bypasses_a_sphere(tmp_path):
    world = parse_world({"name": "s", "robot": {"start": [0, 0, 0]}, "goal": {"position": [2.0, 0.0, 0.5]},
                         "obstacles": [{"kind": "sphere", "center": [1.0, 0.1, 0.2], "radius": 0.25}]})
    r = simulate(world, "apf", params={"v_max": 0.5}, max_time_s=60)
    assert r.outcome == "reached" and r.path.shape[1] == 3 and r.min_clearance_m > 0
    with pytest.raises(ConfigError, match="2-D only"):
        simulate(world, "arapf")
    out = plot_paths(world, {"apf": r.path}, tmp_path / "w3.png")
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_3d_sensor_points_lie_on_the_visible_sphere_surface():
    dirs = fibonacci_directions(500)
    assert np.allclose(np.linalg.norm(dirs, axis=1), 1.0)
    pts = cast_points(np.zeros(3), np.array([[2.0, 0.0, 0.0, 0.5]]), dirs)
    assert pts.shape[0] > 0
    assert np.allclose(np.linalg.norm(pts - [2.0, 0, 0], axis=1), 0.5)
    assert np.all(pts[:, 0] <= 2.0)   # only the near (visible) side


# -- random worlds -------------------------------------------------------------------
def test_random_worlds_are_deterministic_per_seed():
    for i in range(3):
        assert generate(7, i) == generate(7, i)
    assert generate(7, 0) != generate(8, 0)
    assert [generate(7, i).name.rsplit("-", 1)[-1] for i in range(3)] == ["field", "dead_end", "gap"]


def test_random_kinds_and_gap_widths():
    for kind in KINDS:
        w = generate(1, 5, kind)
        assert w.name.endswith(kind) and len(w.obstacles) >= 4      # arena walls at least
    gap = generate(2, 2, "gap")
    barrier = [ob for ob in gap.obstacles[4:6]]
    ends = []
    for ob in barrier:   # the two barrier walls are collinear: the gap = distance between ends
        c, s, h = np.array(ob.center[:2]), np.array([math.cos(ob.yaw), math.sin(ob.yaw)]), ob.size[0] / 2
        ends.append((c - s * h, c + s * h))
    width = min(np.linalg.norm(a - b) for a in ends[0] for b in ends[1])
    assert GAP_RANGE_M[0] - 1e-9 <= width <= GAP_RANGE_M[1] + 1e-9


def test_solvability_rejects_a_blocked_world_and_accepts_a_narrow_gap():
    def barrier(gap):
        lo, hi = -gap / 2, gap / 2
        return corridor([{"kind": "wall", "from": [1.5, -0.8], "to": [1.5, lo], "thickness": 0.1},
                         {"kind": "wall", "from": [1.5, hi], "to": [1.5, 0.8], "thickness": 0.1}])
    assert is_solvable(corridor([]))
    assert is_solvable(barrier(0.45))
    assert not is_solvable(barrier(0.2))       # narrower than the robot's disc
    assert bottleneck_width(barrier(0.6)) == pytest.approx(0.6, abs=2 * 0.05)
    assert bottleneck_width(barrier(0.2)) < 2 * ROBOT_RADIUS_M
    blocked = corridor([{"kind": "wall", "from": [1.5, -0.8], "to": [1.5, 0.8], "thickness": 0.1}])
    assert not is_solvable(blocked)
    worlds, _rejected = generate_solvable(3, seed=4)
    assert len(worlds) == 3 and all(is_solvable(w) for w in worlds)


def test_signed_distance_box_and_cylinder():
    w = parse_world({"goal": {"position": [1, 0]}, "obstacles": [
        {"kind": "box", "center": [0, 0], "size": [2, 1], "yaw": math.pi / 2},
        {"kind": "cylinder", "center": [5, 0], "radius": 1}]})
    d = signed_distance(w, np.array([[0.0, 2.0], [1.0, 0.0], [0.0, 0.0], [5.0, 2.0]]))
    np.testing.assert_allclose(d, [1.0, 0.5, -0.5, 1.0], atol=1e-12)


def test_world_to_toml_round_trip():
    w = generate(3, 1)
    back = parse_world(tomllib.loads(world_to_toml(w)))
    assert back.name == w.name and back.goal == w.goal and back.start == w.start
    for a, b in zip(w.obstacles, back.obstacles, strict=True):
        assert a.shape == b.shape and a.center == b.center and a.size == b.size
        assert a.radius == b.radius and a.yaw == b.yaw


# -- plots -------------------------------------------------------------------------
def test_plot_is_a_valid_png(tmp_path):
    out = plot_paths(load_world("papf-test-4"), {"apf": np.array([[0, 0], [1, 1]]),
                                                 "papf": np.zeros((0, 2))}, tmp_path / "a" / "p.png")
    assert out.read_bytes()[:8] == PNG_MAGIC
    img = mpimg.imread(out)
    assert img.ndim == 3 and img.shape[0] > 100 and img.shape[1] > 100


def test_plan_refuses_its_outputs_before_the_run(tmp_path, capsys):
    import os
    import time

    from papf.cli import main
    from worlds import world_path

    world = tmp_path / "w.toml"
    world.write_text(world_path("papf-test-1").read_text())
    link = tmp_path / "w.csv"
    os.link(world, link)                 # --out a hard link of the world: never, even forced
    mine = tmp_path / "mine.png"
    mine.write_bytes(b"user's")
    for argv, match in ((["--out", str(link), "--force"], "is the input"),
                        (["--plot", str(mine)], "already exists"),
                        (["--out", str(tmp_path / "p.txt")], ".csv or .json"),
                        (["--plot", str(tmp_path / "no" / "p.png")], "does not exist")):
        t0 = time.monotonic()
        assert main(["plan", "--world", str(world), *argv]) == 2
        assert time.monotonic() - t0 < 5.0        # before the run, not after it
        assert match in capsys.readouterr().err
    assert mine.read_bytes() == b"user's" and world.read_text() == link.read_text()


def test_a_forced_plot_replaces_a_symlink_never_its_target(tmp_path):
    from papf.cli import main

    precious = tmp_path / "run.mcap"
    precious.write_bytes(b"recording")
    plot = tmp_path / "p.png"
    plot.symlink_to(precious)
    assert main(["plan", "--world", "papf-test-1", "--timeout", "3", "--plot", str(plot),
                 "--force"]) in (0, 5)
    assert precious.read_bytes() == b"recording"
    assert not plot.is_symlink() and plot.read_bytes()[:4] == b"\x89PNG"
