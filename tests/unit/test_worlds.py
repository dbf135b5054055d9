"""World files: the fixed format parses; broken files give errors naming the problem."""

import math

import pytest

from common.errors import WorldError
from worlds import load_world, packaged_worlds, parse_world

EXAMPLE = """
name = "energy"
description = "PAPF paper IV-C"
[robot]
start = [0.0, 0.0, 0.0]
[goal]
position = [10.0, 0.0]
tolerance = 0.1
[[obstacles]]
kind = "box"
center = [2.5, 0.1]
size = [0.4, 0.4]
yaw = 0.0
[[obstacles]]
kind = "cylinder"
center = [5.0, -0.2]
radius = 0.2
[[obstacles]]
kind = "wall"
from = [7.0, -1.0]
to = [7.0, 1.0]
thickness = 0.05
"""


def write(tmp_path, text, name="w.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_design_example_parses(tmp_path):
    w = load_world(write(tmp_path, EXAMPLE))
    assert w.name == "energy" and w.goal == (10.0, 0.0) and w.tolerance == 0.1
    box, cyl, wall = w.obstacles
    assert box.shape == "box" and box.size == (0.4, 0.4) and box.height == 0.5
    assert cyl.shape == "cylinder" and cyl.radius == 0.2
    assert wall.kind == "wall" and wall.shape == "box"
    assert wall.center == (7.0, 0.0) and wall.size == (2.0, 0.05)
    assert math.isclose(wall.yaw, math.pi / 2)


def test_box_corners_follow_yaw():
    w = parse_world({"goal": {"position": [1, 0]}, "obstacles": [
        {"kind": "box", "center": [1, 1], "size": [2, 1], "yaw": math.pi / 2}]})
    xs = sorted(round(x, 9) for x, _ in w.obstacles[0].corners())
    assert xs == [0.5, 0.5, 1.5, 1.5]


def test_packaged_worlds_load_by_name():
    names = packaged_worlds()
    assert {"open", "energy"} <= set(names)
    for name in names:
        assert load_world(name).name


def test_energy_world_is_the_paper_setup():
    w = load_world("energy")
    assert w.goal == (10.0, 0.0) and len(w.obstacles) == 3


@pytest.mark.parametrize("text, match", [
    ("name = 'x'", r"\[goal\]: is missing"),
    ("[goal]\nposition = [1]", "goal.position: must be an array of 2 numbers or 3 numbers"),
    ("[goal]\nposition = [1, 2]\ntolerance = -1", "goal.tolerance: must be at least 0.005 m"),
    ("[goal]\nposition = [1, 2]\n[[obstacles]]\nkind = 'blob'", "kind: 'blob' is not one of"),
    ("[goal]\nposition = [1, 2]\n[[obstacles]]\nkind = 'box'\ncenter = [1, 1]", r"obstacles\[0\].size: is missing"),
    ("[goal]\nposition = [1, 2]\n[[obstacles]]\nkind = 'cylinder'\ncenter = [1, 1]\nradius = 0", "radius: must be > 0"),
    ("[goal]\nposition = [1, 2]\n[[obstacles]]\nkind = 'wall'\nfrom = [1, 1]\nto = [1, 1]", "same point"),
    ("[goal\nposition = [1, 2]", "not valid TOML"),
])
def test_broken_world_files_say_what_is_wrong(tmp_path, text, match):
    with pytest.raises(WorldError, match=match):
        load_world(write(tmp_path, text))


def test_missing_world_file_lists_packaged_worlds(tmp_path):
    with pytest.raises(WorldError, match="does not exist.*energy"):
        load_world(tmp_path / "nope.toml")
    with pytest.raises(WorldError, match="no packaged world named 'nope'"):
        load_world("nope")


def test_unreadable_bytes(tmp_path):
    p = tmp_path / "bin.toml"
    p.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(WorldError, match="cannot read|not valid TOML"):
        load_world(p)


def test_a_directory_named_like_a_world_does_not_hide_the_packaged_world(tmp_path, monkeypatch):
    from worlds import load_world as _load

    monkeypatch.chdir(tmp_path)
    (tmp_path / "energy").mkdir()             # e.g. `papf experiment energy --out energy`
    assert _load("energy").name == "energy"
