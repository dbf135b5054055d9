"""The social-navigation measures (common/crowd_social.py and their use in
common/crowd_measures.CrowdMeter): hand-computed geometry and counts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.crowd_measures import CrowdMeter, box_corners
from common.crowd_social import (
    HALL_ZONES,
    collision_cause,
    convex_hull,
    extension,
    group_gap,
    polygon_gap,
    time_to_collision,
)
from common.robot import BODY_LENGTH_M, FOOTPRINT_RADIUS_M


def test_hall_zones_are_halls():
    assert HALL_ZONES == (("intimate", 0.45), ("personal", 1.2), ("social", 3.6))


def test_convex_hull_drops_inner_points_and_keeps_two():
    hull = convex_hull(np.array([[0, 0], [2, 0], [1, 1], [2, 2], [0, 2], [1, 0.5]]))
    assert sorted(map(tuple, hull.tolist())) == [(0, 0), (0, 2), (2, 0), (2, 2)]
    assert len(convex_hull(np.array([[0, 0], [1, 0]]))) == 2


def test_polygon_gap_between_boxes_segments_and_points():
    a = box_corners(0.0, 0.0, 0.0)                                 # 0.2 x 0.235 m
    assert polygon_gap(a, np.array([[1.0, -1.0], [1.0, 1.0]])) == pytest.approx(0.9)
    assert polygon_gap(a, np.array([[0.0, -1.0], [0.0, 1.0]])) == 0.0   # through it
    assert polygon_gap(np.array([[0.0, 0.0]]), np.array([[3.0, 4.0]])) == pytest.approx(5.0)


def test_group_space_is_the_hull_of_the_members_grown_by_their_radius():
    members = np.array([[2.0, -0.5], [2.0, 0.5], [2.8, 0.0]])
    inside = box_corners(2.3, 0.0, 0.0)
    assert group_gap(inside, members, 0.25) < 0                      # in the middle: through
    beside = box_corners(2.0, 1.0, 0.0)                               # 0.5 m off one member
    assert group_gap(beside, members, 0.25) == pytest.approx(0.5 - 0.235 / 2 - 0.25)


def test_time_to_collision_head_on_and_never():
    # 3 m apart, closing at 1.5 m/s: discs touch when 3 - r_sum is covered
    t = time_to_collision((0, 0), (0.5, 0), np.array([[3.0, 0.0]]), np.array([[-1.0, 0.0]]),
                          np.array([0.3]))
    assert t == pytest.approx((3.0 - 0.3 - FOOTPRINT_RADIUS_M) / 1.5)
    assert time_to_collision((0, 0), (0, 0), np.array([[3.0, 0.0]]), np.array([[1.0, 0.0]]),
                             np.array([0.3])) == math.inf      # walking away
    assert time_to_collision((0, 0), (0, 0), np.array([[3.0, 2.0]]), np.array([[-1.0, 0.0]]),
                             np.array([0.3])) == math.inf      # passes 2 m aside
    assert time_to_collision((0, 0), (0.1, 0), np.array([[0.4, 0.0]]), np.zeros((1, 2)),
                             np.array([0.3])) == 0.0           # overlapping while closing


def test_who_caused_a_collision_is_who_closed_in_faster():
    assert collision_cause((0, 0), (0.3, 0), (0.5, 0), (0.0, 0)) == "robot"
    assert collision_cause((0, 0), (0.0, 0), (0.5, 0), (-1.0, 0)) == "person"
    assert collision_cause((0, 0), (0.2, 0), (0.5, 0), (-0.2, 0)) == "robot"   # a tie
    assert collision_cause((0, 0), (0.1, 0), (0.5, 0), (0.0, 1.0)) == "robot"  # crossing


def test_extension_compares_only_people_who_reached_their_goal_in_both_runs():
    e = extension([10.0, np.nan, 12.0], [10.5, np.nan, 12.0], [9.0, 8.0, np.nan],
                  [10.0, 8.0, np.nan])
    assert (e.people, e.held) == (1, 1)
    assert (e.path_m, e.time_s) == pytest.approx((0.5, 1.0))
    assert (e.path_pct, e.time_pct) == pytest.approx((5.0, 100.0 / 9.0))
    assert math.isnan(extension([np.nan], [np.nan], [np.nan], [np.nan]).time_s)


def drive_past(meter, ys, person=(3.0, 0.0), radius=0.3, groups_xy=None):
    """The robot along x at 1 m/s from -5 to 10, lateral offset ``ys``, 0.1 s steps."""
    for k, x in enumerate(np.arange(-5.0, 10.0, 0.1)):
        xy = np.array([person] if groups_xy is None else groups_xy)
        meter.update(k * 0.1, {"r": (float(x), ys, 0.0)}, xy, np.full(len(xy), radius))


def test_hall_zones_count_entries_and_time():
    meter = CrowdMeter()
    drive_past(meter, 1.0)                # passes 1 m off the centre: gap 0.583 m
    m = meter.results()["r"]
    assert (m.intimate_n, m.personal_n, m.social_n) == (0, 1, 1)
    assert m.intimate_s == 0.0 and 0 < m.personal_s < m.social_s
    # the social zone: the footprint's front or back within 3.6 m of the disc's edge
    assert m.social_s == pytest.approx(2 * math.sqrt((3.6 + 0.3) ** 2 - (1.0 - 0.1175) ** 2)
                                       + BODY_LENGTH_M, abs=0.15)


def test_group_intrusions_count_driving_between_members_not_past_them():
    pair = [(3.0, -0.6), (3.0, 0.6)]
    through, past = CrowdMeter(groups=((0, 1),)), CrowdMeter(groups=((0, 1),))
    drive_past(through, 0.0, groups_xy=pair, radius=0.25)
    drive_past(past, 1.5, groups_xy=pair, radius=0.25)
    assert through.results()["r"].group_intrusions == 1 and through.results()["r"].group_s > 0
    assert past.results()["r"].group_intrusions == 0


def test_a_group_drifted_apart_holds_no_space():
    split = CrowdMeter(groups=((0, 1),))
    drive_past(split, 0.0, groups_xy=[(3.0, -1.2), (3.0, 1.2)], radius=0.25)   # 1.9 m apart
    assert split.results()["r"].group_intrusions == 0


def test_a_person_of_radius_zero_is_not_there():
    meter = CrowdMeter()
    for k, x in enumerate(np.arange(0.0, 6.0, 0.1)):
        meter.update(k * 0.1, {"r": (float(x), 0.0, 0.0)}, np.array([[3.0, 0.0]]),
                     np.array([0.0]))
    m = meter.results()["r"]
    assert m.min_person_separation_m == math.inf and m.social_n == 0 and m.min_ttc_s == math.inf


def test_min_ttc_of_a_robot_driving_at_a_standing_person():
    meter = CrowdMeter()
    for k, x in enumerate(np.arange(0.0, 2.0, 0.1)):
        meter.update(k * 0.1, {"r": (float(x), 0.0, 0.0)}, np.array([[3.0, 0.0]]),
                     np.array([0.3]), people_v=np.zeros((1, 2)))
    # last step at x = 1.9 m, 1 m/s: discs touch after 3 - 1.9 - 0.3 - 0.154 m
    assert meter.results()["r"].min_ttc_s == pytest.approx(3.0 - 1.9 - 0.3 - FOOTPRINT_RADIUS_M,
                                                           abs=1e-6)
