"""One LiDAR for a whole fleet (``LidarSim(fleet=...)``, ``python -m nodes.lidar_sim --robots``):
every robot's scan bit for bit the scan of a LiDAR of its own."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.lidar_sim.__main__ import build_parser, robots_of
from nodes.lidar_sim.core import LidarParams, LidarSim
from schemas import Bodies
from worlds import load_world

WORLD = """name = "lidar-fleet"
[[robots]]
name = "r1"
start = [0.0, 0.0, 0.0]
goal = [4.0, 0.0]
[[robots]]
name = "r2"
start = [4.0, 0.5, 3.1]
goal = [0.0, 0.5]
[[robots]]
name = "r3"
start = [2.0, -1.0, 1.5]
goal = [2.0, 1.5]
[[robots]]
name = "r4"
start = [1.0, 1.0, -1.5]
goal = [1.0, -1.0]
[[obstacles]]
kind = "wall"
from = [-1.0, -2.0]
to = [6.0, -2.0]
thickness = 0.1
[[obstacles]]
kind = "cylinder"
center = [3.0, 1.2]
radius = 0.3
"""


def views(rng, names, people: int, stamp: int) -> dict[str, Bodies]:
    """Each robot's ``Bodies`` at one instant, as the sim driver makes them: the others at
    one set of poses, the same people for all (some not in the scene: radius 0)."""
    xy = rng.uniform([-0.5, -1.5], [5.0, 1.8], (len(names), 2))
    yaw = rng.uniform(-np.pi, np.pi, len(names))
    px, py = rng.uniform(-0.5, 5.0, people), rng.uniform(-1.5, 1.8, people)
    radius = np.where(rng.random(people) < 0.2, 0.0, rng.uniform(0.15, 0.3, people))
    out = {}
    for i, name in enumerate(names):
        others = [j for j in range(len(names)) if j != i]
        out[name] = Bodies(stamp_ns=stamp, robots=tuple(names[j] for j in others),
                           robot_x=tuple(float(xy[j, 0]) for j in others),
                           robot_y=tuple(float(xy[j, 1]) for j in others),
                           robot_yaw=tuple(float(yaw[j]) for j in others),
                           person_x=tuple(map(float, px)), person_y=tuple(map(float, py)),
                           person_radius=tuple(map(float, radius)))
    return out, xy, yaw


@pytest.mark.parametrize("people", [0, 6])
def test_one_world_gives_each_robot_the_scan_of_its_own_lidar(tmp_path, people):
    path = tmp_path / "w.toml"
    path.write_text(WORLD)
    world = load_world(str(path))
    names = [r.name for r in world.robots]
    params = LidarParams(beams=360)
    rng = np.random.default_rng(7)
    own = [LidarSim(world, params, 3, robot=k) for k in range(len(names))]
    with LidarSim(world, params, 3, fleet=tuple(names)) as shared:
        try:
            hits = 0
            for stamp in range(0, 2_000_000_000, 100_000_000):
                bodies, xy, yaw = views(rng, names, people, stamp)
                for k in rng.permutation(len(names)):   # any order of arrival
                    name = names[k]
                    own[k].place_bodies(bodies[name])
                    shared.place_bodies(bodies[name])
                    pose = (float(xy[k, 0]), float(xy[k, 1]), float(yaw[k]), stamp)
                    alone, fleet = own[k].scan(*pose), shared.scan(*pose, robot=int(k))
                    assert alone.ranges.tobytes() == fleet.ranges.tobytes()
                    hits += int(np.isfinite(fleet.ranges).sum())
            assert hits > 1000   # the scans saw robots, people and obstacles
        finally:
            for lidar in own:
                lidar.close()


def test_robots_must_be_the_worlds(tmp_path):
    from common.errors import ConfigError

    path = tmp_path / "w.toml"
    path.write_text(WORLD)
    world = load_world(str(path))
    args = build_parser().parse_args(["--world", str(path), "--robots", "r1,r3"])
    assert robots_of(args, world) == ["r1", "r3"]
    for bad in ("r1,r9", "r1,r1", ","):
        args = build_parser().parse_args(["--world", str(path), "--robots", bad])
        with pytest.raises(ConfigError, match="names of the world's robots"):
            robots_of(args, world)
    args = build_parser().parse_args(["--world", str(path), "--robots", "r1",
                                      "--pose-source", "odom"])
    with pytest.raises(ConfigError, match="pose-source"):
        robots_of(args, world)
