"""Both sides of a split run in `papf report`: which robot run a laptop recording belongs to,
and which intervals of the robot's odometry the laptop's recording misses (papf.report.sides)."""

from __future__ import annotations

from papf.report.sides import Segment, match, missed

MS = 1_000_000


def test_the_laptop_misses_exactly_the_robot_samples_it_does_not_hold():
    robot = list(range(0, 10_000 * MS, 20 * MS))               # 50 Hz for 10 s
    laptop = [t for t in robot if not 3_000 * MS <= t < 5_000 * MS and t != 7_000 * MS]
    assert missed(laptop, robot, t_end_ns=9_000 * MS) == [(3.0, 4.98)]   # one sample: no hole


def test_what_comes_after_the_outcome_is_not_missed():
    robot = list(range(0, 2_000 * MS, 20 * MS))
    assert missed(robot[:60], robot, t_end_ns=1_100 * MS) == []
    assert missed([], robot, t_end_ns=1_100 * MS) == [(0.0, 1.1)]


def test_a_laptop_run_finds_its_robot_run_by_the_launchers_result():
    segs = [Segment(0, 1, 2, '{"outcome": "reached", "wall_time_s": 1.5}'),
            Segment(1, 3, 4, '{"outcome": "timeout", "wall_time_s": 9.1}')]
    assert match('{"outcome": "timeout", "wall_time_s": 9.1}', segs) is segs[1]
    assert match('{"outcome": "x"}', segs) is None            # two runs, neither its own
    assert match("", segs[:1]) is segs[0]                     # the one run there is
