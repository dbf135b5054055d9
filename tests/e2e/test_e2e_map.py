"""End to end: a bare ROS map YAML made here runs through the stack — the LiDAR casts and
the driver collides against its walls — and PAPF reaches the goal without a collision."""

import pytest

from papf.offline import map_gen
from tests.support.e2e import papf_run
from worlds.maps import OccupancyMap, save_map

pytestmark = pytest.mark.e2e


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_papf_crosses_a_map_of_rooms(tmp_path):
    yaml_path, _ = save_map(OccupancyMap(map_gen.rooms(0.05), 0.05, (-1.0, -0.5, 0.0)),
                            tmp_path / "lab.yaml")
    code, res, err = papf_run("--world", str(yaml_path), "--start=1.5,1.5", "--goal=9.5,3.0",
                              "--planner", "papf", "--seed", "1", "--timeout", "200")
    assert res is not None, err
    assert (code, res["outcome"], res["collisions"]) == (0, "reached", 0), err
    assert res["world"] == "lab" and 8.0 <= res["path_length_m"] <= 11.0
