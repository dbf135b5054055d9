"""Roads and moving obstacles in world files: parsing, errors, interpolation and heading."""

import math

import pytest

from common.errors import WorldError
from schemas.messages import Goal
from tests.support.worlds import traffic_world
from worlds import load_world, parse_world
from worlds.messages import goal_message
from worlds.traffic import Motion, Road, RoadLine, heading_at, pose_at, state_at

ISSUE_EXAMPLE = traffic_world(track=((0.0, 3.0, 0.0), (20.0, 5.0, 0.0), (28.0, 5.0, 0.6)))


def write(tmp_path, text, name="w.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_issue_example_parses(tmp_path):
    w = load_world(write(tmp_path, ISSUE_EXAMPLE))
    assert w.road == Road(y_min=-0.3, lane_width=0.6, lanes=2)
    (car,) = w.obstacles
    assert car.moving and w.has_motion
    assert car.center == (3.0, 0.0) and car.yaw == 0.0   # track at t = 0, heading +x
    assert car.motion.track[-1] == (28.0, 5.0, 0.6)


def test_road_lines_and_lanes():
    road = Road(y_min=-0.3, lane_width=0.6, lanes=2)
    assert road.y_max == pytest.approx(0.9)
    lines = road.lines()
    assert [ln.kind for ln in lines] == ["solid", "broken", "solid"]
    assert [ln.y for ln in lines] == pytest.approx([-0.3, 0.3, 0.9])
    assert road.lane_centres() == pytest.approx((0.0, 0.6))
    assert road.lane_of(-0.1) == 0 and road.lane_of(0.31) == 1 and road.lane_of(5.0) == 1
    assert road.on_road(0.9) and not road.on_road(0.91) and not road.on_road(-0.31)
    assert Road(0.0, 1.0, 1).lines() == (RoadLine(0.0, "solid"), RoadLine(1.0, "solid"))


MOTION = Motion(track=((0.0, 3.0, 0.0), (20.0, 5.0, 0.0), (28.0, 5.0, 0.6)), yaw0=0.3)


@pytest.mark.parametrize("t, pose", [
    (-5.0, (3.0, 0.0, 0.3)),          # held before the first sample, heading = yaw
    (0.0, (3.0, 0.0, 0.0)),
    (10.0, (4.0, 0.0, 0.0)),          # halfway: 3 + 0.5 * 2
    (24.0, (5.0, 0.3, math.pi / 2)),  # halfway along the sideways segment, heading +y
    (28.0, (5.0, 0.6, math.pi / 2)),  # last sample: kept heading
    (99.0, (5.0, 0.6, math.pi / 2)),  # held after
])
def test_track_interpolates_linearly_and_holds(t, pose):
    assert pose_at(MOTION, t) == pytest.approx(pose)


def test_velocity_is_the_segment_slope_and_zero_outside():
    assert (state_at(MOTION, 5.0).vx, state_at(MOTION, 5.0).vy) == pytest.approx((0.1, 0.0))
    assert (state_at(MOTION, 21.0).vx, state_at(MOTION, 21.0).vy) == pytest.approx((0.0, 0.075))
    assert (state_at(MOTION, -1.0).vx, state_at(MOTION, 30.0).vy) == (0.0, 0.0)


def test_heading_kept_while_standing_and_yaw_before_first_move():
    m = Motion(track=((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (4.0, -1.0, -1.0), (6.0, -1.0, -1.0),
                      (8.0, 0.0, -1.0)), yaw0=0.7)
    assert heading_at(m, -1.0) == 0.7 and heading_at(m, 1.0) == 0.7   # standing at first: yaw
    assert heading_at(m, 3.0) == pytest.approx(-3 * math.pi / 4)      # towards (-1, -1)
    assert heading_at(m, 5.0) == pytest.approx(-3 * math.pi / 4)      # standing: kept
    assert heading_at(m, 7.0) == pytest.approx(0.0)                   # moving +x
    assert heading_at(m, 50.0) == pytest.approx(0.0)                  # after the end: kept


def test_obstacle_at_places_moving_and_keeps_static():
    w = parse_world({"goal": {"position": [9, 0]}, "obstacles": [
        {"kind": "cylinder", "center": [1, 1], "radius": 0.2},
        {"kind": "cylinder", "radius": 0.2, "yaw": 1.0,
         "motion": {"track": [[1.0, 0.0, 0.0], [3.0, 0.0, 2.0]]}}]})
    static, moving = w.obstacles
    assert static.at(7.0) is static
    assert moving.center == (0.0, 0.0) and moving.yaw == 1.0          # before the first move
    placed = w.obstacles_at(2.0)[1]
    assert placed.center == pytest.approx((0.0, 1.0)) and placed.yaw == pytest.approx(math.pi / 2)
    assert moving.state_at(2.0).vy == pytest.approx(1.0)


def test_moving_wall_keeps_its_length_and_follows_the_track():
    w = parse_world({"goal": {"position": [9, 0]}, "obstacles": [
        {"kind": "wall", "from": [0, -0.5], "to": [0, 0.5],
         "motion": {"track": [[0.0, 2.0, 0.0], [1.0, 2.0, 0.0]]}}]})
    (wall,) = w.obstacles
    assert wall.center == (2.0, 0.0) and wall.size == (1.0, 0.05)
    assert wall.yaw == pytest.approx(math.pi / 2)   # standing: from -> to gives the heading


def test_center_that_agrees_with_the_track_is_accepted():
    w = parse_world({"goal": {"position": [9, 0]}, "obstacles": [
        {"kind": "box", "center": [3, 0], "size": [1, 1],
         "motion": {"track": [[0.0, 3.0, 0.0], [1.0, 4.0, 0.0]]}}]})
    assert w.obstacles[0].center == (3.0, 0.0)


BASE = "[goal]\nposition = [9, 0]\n"
BOX = "[[obstacles]]\nkind = 'box'\nsize = [1, 1]\n"


@pytest.mark.parametrize("text, match", [
    (BASE + "[road]\nlane_width = 0.6\nlanes = 2", r"road.y_min: is missing"),
    (BASE + "[road]\ny_min = 0\nlane_width = 0\nlanes = 2", r"road.lane_width: must be > 0"),
    (BASE + "[road]\ny_min = 0\nlane_width = 0.6\nlanes = 1.5", r"road.lanes: must be an integer >= 1"),
    (BASE + "[road]\ny_min = 0\nlane_width = 0.6", r"road.lanes: is missing"),
    ("road = 3\n" + BASE, r"\[road\]: must be a table"),
    (BASE + BOX, r"obstacles\[0\].center: is missing"),
    (BASE + BOX + "[obstacles.motion]\n", r"obstacles\[0\].motion.track: is missing"),
    (BASE + BOX + "[obstacles.motion]\ntrack = []", r"obstacles\[0\].motion.track: must be a non-empty"),
    (BASE + BOX + "[obstacles.motion]\ntrack = [[0, 1]]", r"obstacles\[0\].motion.track\[0\]: must be an array of 3"),
    (BASE + BOX + "[obstacles.motion]\ntrack = [[0, 1, 1], [0, 2, 2]]",
     r"obstacles\[0\].motion.track\[1\]: time 0.0 s must be after"),
    (BASE + BOX + "center = [5, 5]\n[obstacles.motion]\ntrack = [[0, 1, 1]]",
     r"obstacles\[0\].center: \[5.0, 5.0\] is not where the track is at t = 0"),
    (BASE + BOX + "motion = 1", r"obstacles\[0\].motion: must be a table"),
    ("[goal]\nposition = [9, 0, 1]\n[[obstacles]]\nkind = 'sphere'\ncenter = [1, 1, 1]\nradius = 1\n"
     "[obstacles.motion]\ntrack = [[0, 1, 1]]", r"obstacles\[0\].motion: only 2-D kinds"),
    ("[goal]\nposition = [9, 0, 1]\n[road]\ny_min = 0\nlane_width = 1\nlanes = 1",
     r"\[road\]: a road needs a 2-D world"),
])
def test_broken_traffic_entries_name_file_and_entry(tmp_path, text, match):
    path = write(tmp_path, text, "bad.toml")
    with pytest.raises(WorldError, match=match) as info:
        load_world(path)
    assert "bad.toml" in str(info.value)


def test_goal_message_carries_the_road(tmp_path):
    goal = goal_message(load_world(write(tmp_path, ISSUE_EXAMPLE)))
    back = Goal.from_bytes(goal.to_bytes())
    assert (back.road_lanes, back.road_y_min, back.road_lane_width) == (2, -0.3, 0.6)
    assert Road.from_fields(back.road_lanes, back.road_y_min, back.road_lane_width) == \
        Road(-0.3, 0.6, 2)
    assert goal_message(load_world("open")).road_lanes == 0
    assert Road.from_fields(0, 0.0, 0.0) is None
