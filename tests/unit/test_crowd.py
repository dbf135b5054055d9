"""common/crowd.py: people walked by ORCA (pyrvo) and the social-force model (pysocialforce)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from common.crowd import Crowd, obstacle_polygons
from common.robot import FOOTPRINT_RADIUS_M
from worlds import World
from worlds.fleet import PersonSpec
from worlds.kinds.wall import segment_wall

CORRIDOR = (segment_wall(-1, 1.0, 11, 1.0), segment_wall(-1, -1.0, 11, -1.0))


def _world(obstacles=()):
    return World("t", "", (0.0, 0.0, 0.0), (1.0, 0.0), 0.1, obstacles=tuple(obstacles))


def _walk(crowd, steps, robots=(), dt=0.1):
    """Positions (steps, n, 2) [m] of ``steps`` steps."""
    out = []
    for _ in range(steps):
        crowd.step(dt, robots)
        out.append(crowd.positions)
    return np.array(out)


def test_orca_head_on_in_a_corridor_pass_without_contact():
    people = [PersonSpec((0, 0), ((10, 0),)), PersonSpec((10, 0), ((0, 0),))]
    track = _walk(Crowd(people, _world(CORRIDOR), seed=1), 250)
    gap = np.hypot(*(track[:, 0] - track[:, 1]).T) - 0.6
    assert gap.min() > 0.0                              # never touched
    assert np.abs(track[..., 1]).max() < 1.0 - 0.3      # inside the corridor
    assert np.abs(track[..., 1]).max() > 0.2            # stepped aside to pass


def test_orca_person_walks_around_a_robot_in_its_way():
    crowd = Crowd([PersonSpec((0, 0), ((10, 0),))], _world(CORRIDOR), seed=3)
    track = _walk(crowd, 250, robots=[(5.0, 0.05, 0.0, 0.0)])
    gap = np.hypot(track[:, 0, 0] - 5.0, track[:, 0, 1] - 0.05) - 0.3 - FOOTPRINT_RADIUS_M
    assert gap.min() > 0.0
    assert crowd.arrived().all()


def test_social_force_head_on_in_the_open_step_aside_and_arrive():
    people = [PersonSpec((0, 0), ((10, 0),), model="social_force"),
              PersonSpec((10, 0), ((0, 0),), model="social_force")]
    crowd = Crowd(people, _world(), seed=1)
    track = _walk(crowd, 200)
    gap = np.hypot(*(track[:, 0] - track[:, 1]).T) - 0.6
    assert np.abs(track[..., 1]).max() > 0.3   # the social force turns them aside
    assert gap.min() > -0.1                    # no radius in the model: a brush, not a pass-through
    assert crowd.arrived().all()


def test_same_seed_same_positions_bit_for_bit_and_mixed_models():
    people = [PersonSpec((0, 0), ((6, 0),)), PersonSpec((6, 0.1), ((0, 0),), model="social_force"),
              PersonSpec((3, -3), ((3, 3), (3, -3)), loop=True)]
    runs = [_walk(Crowd(people, _world(CORRIDOR[:1]), seed=s), 60, robots=[(3, 0, 0.2, 0)])
            for s in (7, 7, 8)]
    assert np.array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])


def test_waypoints_advance_within_the_radius_and_loop():
    square = ((2, 0), (2, 2), (0, 2), (0, 0))
    looping = Crowd([PersonSpec((0, 0), square, loop=True)], _world(), seed=0)
    track = _walk(looping, 200)
    for wx, wy in square:
        assert np.hypot(track[:, 0, 0] - wx, track[:, 0, 1] - wy).min() <= 0.3
    assert not looping.arrived().any()
    once = Crowd([PersonSpec((0, 0), square[:2])], _world(), seed=0)
    _walk(once, 60)
    assert once.arrived().all()
    np.testing.assert_allclose(once.velocities, 0.0, atol=1e-3)


def test_people_keep_out_of_boxes_and_cylinders():
    from worlds.obstacle import Obstacle
    box = Obstacle("box", "box", (3.0, 0.0), size=(1.0, 1.0))
    cyl = Obstacle("cylinder", "cylinder", (7.0, 0.2), radius=0.5)
    world = _world([box, cyl])
    assert [len(p) for p in obstacle_polygons(world)] == [4, 16]
    for model in ("orca", "social_force"):
        track = _walk(Crowd([PersonSpec((0, 0.05), ((10, 0),), model=model)], world, seed=2), 200)
        in_box = (np.abs(track[:, 0, 0] - 3) < 0.5) & (np.abs(track[:, 0, 1]) < 0.5)
        assert not in_box.any(), model
        assert (np.hypot(track[:, 0, 0] - 7, track[:, 0, 1] - 0.2) > 0.5).all(), model


def test_the_social_force_library_leaves_logging_and_cwd_alone(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    root = logging.getLogger()
    before = (root.level, list(root.handlers))
    _walk(Crowd([PersonSpec((0, 0), ((1, 0),), model="social_force")], _world(), seed=0), 2)
    assert (root.level, list(root.handlers)) == before
    assert not list(tmp_path.iterdir())


def test_bad_steps_are_refused():
    crowd = Crowd([PersonSpec((0, 0), ((1, 0),))], _world(), seed=0)
    with pytest.raises(ValueError, match="dt_s"):
        crowd.step(0.0, [])
    crowd.step(0.1, [(5, 5, 0, 0)])
    with pytest.raises(ValueError, match="robots"):
        crowd.step(0.1, [])
