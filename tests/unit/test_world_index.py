"""worlds/index.py: the nearest static obstacle by place equals the one found by walking all."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from worlds import parse_world
from worlds.index import StaticIndex


def _world(n: int, seed: int):
    rng = np.random.default_rng(seed)
    obs = [{"kind": "cylinder", "center": [float(x), float(y)], "radius": float(r)}
           for x, y, r in zip(rng.uniform(-30, 30, n), rng.uniform(-30, 30, n),
                              rng.uniform(0.05, 2.0, n), strict=True)]
    obs.append({"kind": "wall", "from": [-40.0, 35.0], "to": [40.0, 35.0]})   # kept aside
    obs.append({"kind": "box", "center": [50.0, 0.0], "size": [1.0, 1.0],
                "motion": {"track": [[0.0, 50.0, 0.0], [5.0, 51.0, 0.0]]}})   # moving: not filed
    return parse_world({"goal": {"position": [0.0, 0.0]}, "obstacles": obs})


def _walk(world, x, y):
    ds = [(float(ob.model.distance(ob, np.array([[x, y]]))[0]), i)
          for i, ob in enumerate(world.obstacles) if ob.motion is None]
    return min(ds)[1]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 1000), st.floats(-60, 60), st.floats(-60, 60), st.sampled_from([0.5, 1.0, 3.0]))
def test_nearest_equals_the_walk_over_every_obstacle(seed, x, y, cell):
    world = _world(40, seed)
    assert StaticIndex(world, cell).nearest(x, y) == _walk(world, x, y)


def test_a_moving_obstacle_is_never_named_and_an_empty_world_has_none():
    world = _world(0, 1)
    index = StaticIndex(world)
    assert index.nearest(50.0, 0.0) == 0           # the wall, not the moving box on the spot
    assert StaticIndex(parse_world({"goal": {"position": [1.0, 0.0]}})).nearest(0, 0) is None


def test_a_long_wall_is_kept_aside_and_found_from_anywhere():
    world = _world(5, 2)
    index = StaticIndex(world, 0.01)
    assert len(world.obstacles) - 2 in index.wide
    assert len(world.obstacles) - 2 in index.near(-39.0, 34.0, 0.1)
