"""End to end: two robots swap the ends of a corridor head-on in one `papf run`: each
LiDAR sees the other robot, both reach, nothing collides, and one seed gives one result."""

from __future__ import annotations

from tests.support.e2e import papf_run

HEAD_ON = """name = "swap"
description = "two ROSbots head-on in a 2 m corridor"
[[robots]]
name = "r1"
start = [0.0, 0.0, 0.0]
goal = [3.0, 0.0]
[[robots]]
name = "r2"
start = [3.0, 0.0, 3.14159265]
goal = [0.0, 0.0]
[[obstacles]]
kind = "wall"
from = [-1.0, -1.0]
to = [4.0, -1.0]
[[obstacles]]
kind = "wall"
from = [-1.0, 1.0]
to = [4.0, 1.0]
"""


def test_corridor_swap_head_on_both_reach_and_repeat(tmp_path):
    world = tmp_path / "swap.toml"
    world.write_text(HEAD_ON)
    runs = [papf_run("--world", str(world), "--planner", "papf", "--seed", "2", "--timeout", "60")
            for _ in range(2)]
    for code, res, err in runs:
        assert res is not None, err
        assert (code, res["outcome"], res["collisions"]) == (0, "reached", 0), res
        assert [r["name"] for r in res["robots"]] == ["r1", "r2"]
        assert all(r["outcome"] == "reached" and r["collisions"] == 0 for r in res["robots"])
        assert 0 < res["min_separation_m"] < 1.0   # they passed each other, apart
    first, second = (dict(res, wall_time_s=None) for _, res, _ in runs)
    assert first == second
