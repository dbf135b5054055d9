"""The IAPF paper's cases A-D at car scale, offline (papf/offline/road.py): the acceptance of
issue 11 — IAPF never touches a vehicle nor leaves the road, follows in case C and changes
lanes in A, B and D. The traditional APF baseline runs too (its outcome is reported in
docs/planners.md, not asserted beyond what the paper shows)."""

import json

import pytest

from papf.offline.road import car_params, run_car
from tests.support.cli import papf
from worlds import load_world

CASE_TIME_S = {"a": 5.0, "b": 5.0, "c": 6.0, "d": 10.0}   # Table 2


@pytest.mark.parametrize("case", "abcd")
def test_iapf_cases_collision_free_on_the_road(case):
    run = run_car(load_world(f"iapf-case-{case}"), "iapf", duration_s=CASE_TIME_S[case])
    assert run.collisions == 0 and run.min_clearance_m > 0.3
    assert not run.left_road
    if case == "c":        # car following: no lane change, the speed settles near the leader's
        assert run.lane_changes == 0
        assert abs(run.states[-1, 2] - 8.0) < 1.0 and run.states[:, 2].min() > 7.0
    else:
        assert run.lane_changes >= 1
    if case in "bd":       # the local minimum is found and a temporary lane goal is set
        assert (run.local_counts > car_params("iapf").c_f).any()


def test_case_b_without_prediction_is_trapped_at_the_solid_line():
    run = run_car(load_world("iapf-case-b"), "iapf-np", duration_s=5.0)
    assert run.left_road and run.lane_changes == 0


def test_traditional_apf_keeps_its_speed_and_fails_case_b():
    run = run_car(load_world("iapf-case-b"), "apf", duration_s=5.0)
    assert (run.states[:, 2] == 10.0).all()
    assert run.left_road or run.collisions > 0


def test_plan_json_on_a_road_world_has_the_road_figures():
    r = papf("plan", "--world", "iapf-case-c", "--planner", "iapf", "--json", timeout=120)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["outcome"] == "reached" and out["collisions"] == 0 and out["left_road"] is False
    assert out["lane_changes"] == 0 and 7.0 < out["min_speed_mps"] < out["max_speed_mps"] <= 10.0
    assert out["min_clearance_m"] > 0


def test_plan_refuses_scan_planners_on_car_worlds():
    r = papf("plan", "--world", "iapf-case-a", "--planner", "papf", timeout=120)
    assert r.returncode == 2 and "valid" in r.stderr and "Traceback" not in r.stderr
