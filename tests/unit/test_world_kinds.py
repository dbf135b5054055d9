"""Obstacle kinds as classes (worlds/kinds/): each kind's parsing, geometry, physics body and
drawing agree with each other, and a new kind is one class and one registration."""

import math

import matplotlib
import numpy as np
import pytest

from common.errors import WorldError
from common.quiet import import_quietly
from nodes.viewer.scene import world_scene
from papf.offline.world_gen import world_to_toml
from papf.plots.world import draw_world, new_axes
from worlds import KINDS, parse_world
from worlds.bullet import build_world
from worlds.checks import nearest_obstacle
from worlds.geometry import cast_rays, signed_distance
from worlds.kinds.base import Outline, Solid
from worlds.kinds.box import Box
from worlds.obstacle import Obstacle

matplotlib.use("Agg")
p = import_quietly("pybullet")

TABLES = {
    "box": {"kind": "box", "center": [2.0, 0.5], "size": [0.6, 0.3], "yaw": 0.4},
    "cylinder": {"kind": "cylinder", "center": [2.0, -0.5], "radius": 0.3},
    "wall": {"kind": "wall", "from": [1.5, 1.5], "to": [2.5, 2.0], "thickness": 0.1},
}


def world_of(*tables, goal=(5.0, 0.0)):
    return parse_world({"goal": {"position": list(goal)}, "obstacles": list(tables)})


def test_every_planar_kind_has_a_table_here():
    planar = {name for name, k in KINDS.items() if 2 in k.world_dims and k.listed}
    assert planar == set(TABLES)


@pytest.mark.parametrize("name", sorted(TABLES))
def test_table_parses_back_to_the_same_obstacle(name):
    ob = world_of(TABLES[name]).obstacles[0]
    again = world_of(ob.model.table(ob)).obstacles[0]
    assert again.shape == ob.shape and again.center == ob.center
    assert again.size == pytest.approx(ob.size) and again.radius == ob.radius
    assert again.yaw == pytest.approx(ob.yaw)


@pytest.mark.parametrize("name", sorted(TABLES))
def test_ray_hits_lie_on_the_outline(name):
    world = world_of(TABLES[name])
    angles = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    ranges = cast_rays(world, 0.0, 0.0, angles)
    hit = np.isfinite(ranges)
    assert hit.any()
    r, a = ranges[hit], angles[hit]
    pts = np.column_stack([r * np.cos(a), r * np.sin(a)])
    assert np.abs(signed_distance(world, pts)).max() < 1e-9


@pytest.mark.parametrize("name", sorted(TABLES))
def test_pybullet_body_is_the_same_geometry(name):
    """The LiDAR's pybullet rays see what the plain geometry's rays see."""
    world = world_of(TABLES[name])
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    exact = cast_rays(world, 0.0, 0.0, angles, range_max=10.0)
    cid = p.connect(p.DIRECT)
    try:
        build_world(cid, world)
        ends = [(10 * math.cos(a), 10 * math.sin(a), 0.2) for a in angles]
        hits = p.rayTestBatch([(0.0, 0.0, 0.2)] * len(ends), ends, physicsClientId=cid)
    finally:
        p.disconnect(cid)
    seen = np.array([h[2] * 10 if h[0] >= 0 else np.inf for h in hits])
    both = np.isfinite(exact) & np.isfinite(seen)
    assert (np.isfinite(exact) == np.isfinite(seen)).mean() > 0.98   # grazing rays may differ
    assert np.abs(exact[both] - seen[both]).max() < 0.01


def test_sphere_is_an_obstacle_of_3d_worlds_only():
    world = parse_world({"robot": {"start": [0.0, 0.0, 0.0]}, "goal": {"position": [5.0, 0, 0]},
                         "obstacles": [{"kind": "sphere", "center": [2.0, 0.0, 0.0],
                                        "radius": 0.5}]})
    assert nearest_obstacle(world, (0.0, 0.0, 0.0)) == (0, pytest.approx(1.5))
    with pytest.raises(WorldError, match="only 2-D kinds \\(box, cylinder, wall\\)"):
        parse_world({"goal": {"position": [5.0, 0.0]}, "obstacles": [
            {"kind": "sphere", "center": [2.0, 0.0, 0.0], "radius": 0.5,
             "motion": {"track": [[0, 2, 0], [1, 3, 0]]}}]})


def test_unknown_kind_names_the_registered_ones():
    with pytest.raises(WorldError, match="'cone' is not one of box, cylinder, wall, sphere$"):
        world_of({"kind": "cone", "center": [1.0, 1.0]})


class Post(Box):
    """A square post: ``side`` [m] — a kind only this test knows."""

    name = "post"
    keys = ("center", "side", "height")   # its TOML keys: the world check derives from them

    def parse(self, ctx, table, where):
        side = ctx.positive(table, "side", f"{where}.side")
        center = ctx.vec(table, "center", (2,), f"{where}.center")
        return Obstacle(self.name, "box", tuple(center), (side, side))

    def table(self, ob):
        return {"kind": self.name, "center": list(ob.center), "side": ob.size[0]}


def test_a_new_kind_is_one_class_and_one_registration(monkeypatch):
    monkeypatch.setitem(KINDS, "post", Post())
    world = world_of({"kind": "post", "center": [2.0, 0.0], "side": 0.5})
    ob = world.obstacles[0]
    assert cast_rays(world, 0.0, 0.0, np.array([0.0]))[0] == pytest.approx(1.75)
    assert nearest_obstacle(world, (0.0, 0.0)) == (0, pytest.approx(1.75))
    assert isinstance(ob.model.drawing(ob), Outline) and isinstance(ob.model.solids(ob)[0], Solid)
    fig, ax = new_axes(world)
    draw_world(ax, world)
    assert len(ax.patches) == 2          # the post and the goal's tolerance circle
    matplotlib.pyplot.close(fig)
    cubes = world_scene(world)["entities"][0]["cubes"]
    assert [c["size"]["x"] for c in cubes] == [0.5]
    assert 'kind = "post"' in world_to_toml(world)
    cid = p.connect(p.DIRECT)
    try:
        assert len(build_world(cid, world)) == 1
    finally:
        p.disconnect(cid)
    with pytest.raises(WorldError, match="side"):
        world_of({"kind": "post", "center": [2.0, 0.0]})


def test_a_map_is_no_obstacles_entry():
    with pytest.raises(WorldError, match="'map' is not one of"):
        world_of({"kind": "map", "file": "x.yaml"})


def test_many_static_obstacles_are_merged_into_meshes_that_rays_and_contacts_see():
    """Beyond MERGE_MIN static obstacles pybullet holds meshes, not a body each: the LiDAR's
    rays see the same obstacles (cylinders as circumscribed 16-gons) and a contact with a
    mesh names the obstacle touched."""
    from nodes.world_sim.physics import SimBase
    from worlds.bullet import MERGE_MIN, MERGED, TILE_M

    rng = np.random.default_rng(3)
    obs = [{"kind": "cylinder", "center": [float(x), float(y)], "radius": 0.15}
           for x, y in rng.uniform(2, 12, (MERGE_MIN + 40, 2))]
    obs += [{"kind": "box", "center": [0.0, 2.0], "size": [0.4, 0.2], "yaw": 0.3}]
    world = world_of(*obs, goal=(1.0, 0.0))
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    exact = cast_rays(world, 0.0, 0.0, angles, range_max=15.0)
    owners = {}
    cid = p.connect(p.DIRECT)
    try:
        ids = build_world(cid, world, owners)
        ends = [(15 * math.cos(a), 15 * math.sin(a), 0.2) for a in angles]
        hits = p.rayTestBatch([(0.0, 0.0, 0.2)] * len(ends), ends, physicsClientId=cid)
    finally:
        p.disconnect(cid)
    # one mesh per 10 m tile the obstacles' centres fall in (2..12 m: tiles 0 and 1 each way)
    tiles = {(math.floor(o["center"][0] / TILE_M), math.floor(o["center"][1] / TILE_M)) for o in obs}
    assert set(owners.values()) == {MERGED} and set(ids) == set(owners) and len(owners) == len(tiles)
    for ob, body in zip(obs, ids, strict=True):   # each obstacle in the mesh of its own tile
        same = [b for o, b in zip(obs, ids, strict=True)
                if math.floor(o["center"][0] / TILE_M) == math.floor(ob["center"][0] / TILE_M)
                and math.floor(o["center"][1] / TILE_M) == math.floor(ob["center"][1] / TILE_M)]
        assert set(same) == {body}
    seen = np.array([h[2] * 15 if h[0] >= 0 else np.inf for h in hits])
    both = np.isfinite(exact) & np.isfinite(seen)
    assert both.sum() > 50 and (np.isfinite(exact) == np.isfinite(seen)).mean() > 0.97
    assert (seen[both] <= exact[both] + 1e-6).all()           # a 16-gon holds its circle
    assert (exact[both] - seen[both] < 0.02).mean() > 0.9     # grazing rays aside
    sim = SimBase(parse_world({"robot": {"start": [0.0, 1.55, 1.5708]}, "goal": {"position": [0.0, 1.0]},
                               "obstacles": obs}))
    try:
        sim.set_twist(0.5, 0.0)
        touched = set()
        for _ in range(400):                                 # 1.6 s at 4 ms: into the box
            sim.step()
            touched |= {c.obstacle for c in sim.contacts()}
    finally:
        sim.close()
    assert touched == {len(obs) - 1}                         # the box, by its index
