"""World files: the fixed format parses; broken files give errors naming the problem."""

import json
import math
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common.errors import WorldError
from tests.support.cli import papf
from worlds import load_world, packaged_worlds, parse_world, world_data
from worlds.checks import check_runnable
from worlds.kinds import KINDS
from worlds.validate import MAX_LANES, MAX_TRACK_POINTS, TOP

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


SETTINGS = settings(max_examples=60, deadline=None)
BASE = world_data("energy-blocking")


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


@pytest.mark.parametrize("tolerance", [0.0, 1e-300, -1.0, 0.004])
def test_a_goal_tolerance_below_the_floor_is_refused_by_goal_and_worlds(tolerance, capsys):
    from common.errors import WorldError
    from papf.cli import main
    from worlds import parse_world

    with pytest.raises(SystemExit) as exc:
        main(["goal", "1", "0", "--tolerance", repr(tolerance)])
    assert exc.value.code == 2 and "0.005" in capsys.readouterr().err
    with pytest.raises(WorldError, match="at least 0.005 m"):
        parse_world({"goal": {"position": [1.0, 0.0], "tolerance": tolerance}}, "t")


@SETTINGS
@given(st.text(max_size=120))
def test_a_world_name_that_is_taken_is_a_plain_file_name(name):
    from common.errors import WorldError
    from worlds import parse_world, world_data

    data = {**world_data("papf-test-1"), "name": name}
    try:
        world = parse_world(data, "w.toml")
    except WorldError as exc:
        assert "\x1b" not in str(exc) and "\n" not in str(exc)
        return
    assert world.name.isprintable() and "/" not in world.name and "\\" not in world.name
    assert not world.name.startswith(".") and len(world.name) <= 100


@pytest.mark.parametrize("stem", ["my world (copy)", ".hidden", "\x1b[2Jx", "a" * 300])
def test_a_default_world_name_is_the_file_stem_made_plain(stem):
    from worlds import parse_world, world_data

    data = {k: v for k, v in world_data("papf-test-1").items() if k != "name"}
    name = parse_world(data, f"/tmp/{stem}.toml").name
    assert name.isprintable() and not name.startswith(".") and 0 < len(name) <= 100


def _with(**top) -> dict:
    return {**json.loads(json.dumps(BASE)), **top}


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.text(st.characters(min_codepoint=97, max_codepoint=122), min_size=1, max_size=12))
def test_any_unknown_obstacle_key_is_refused(key):
    data = _with()
    ob = data["obstacles"][1]   # a cylinder
    if key in ("kind", *KINDS["cylinder"].keys):
        return
    ob[key] = 2.0
    with pytest.raises(WorldError, match=r"obstacles\[1\]\." + key + ": unknown key"):
        parse_world(data, "w.toml")


@pytest.mark.parametrize("data,match", [
    ({"hieght": 2.0}, "did you mean 'height'"),
])
def test_a_misspelt_key_says_what_was_meant(data, match):
    world = _with()
    world["obstacles"][1].update(data)
    with pytest.raises(WorldError, match=match):
        parse_world(world, "w.toml")


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(table=st.text(st.characters(min_codepoint=97, max_codepoint=122), min_size=1, max_size=10))
def test_any_unknown_table_is_refused(table):
    if table in TOP:
        return
    with pytest.raises(WorldError, match="unknown key"):
        parse_world(_with(**{table: {"x": 1}}), "w.toml")


@pytest.mark.parametrize("extra,match", [
    ({"road": {"y_min": -1.0, "lane_width": 1.0, "lanes": 10**9}}, f"more than {MAX_LANES}"),
    ({"name": "x" * 1000}, "characters, more than"),
    ({"obstacles": [{"kind": "box", "size": [0.1, 0.1],
                     "motion": {"track": [[float(t), 5.0, 5.0] for t in range(MAX_TRACK_POINTS + 1)]}}]},
     "points, more than"),
])
def test_sizes_a_world_may_ask_for_are_bounded(extra, match):
    with pytest.raises(WorldError, match=match):
        parse_world(_with(**extra), "w.toml")


@pytest.mark.parametrize("text,match", [
    ("a = " + "[" * 50_000 + "]" * 50_000 + "\n", "nested too deeply"),
    ('name = "' + "x" * 2_000_000 + '"\n', "more than the 1,048,576"),
    ("a = " + "[" * 10 + "]" * 10 + "\n", "nested deeper than"),
])
def test_hostile_files_fail_fast_in_one_line(tmp_path, text, match):
    f = tmp_path / "w.toml"
    f.write_text(text)
    t0 = time.monotonic()
    with pytest.raises(WorldError, match=match) as exc:
        load_world(f)
    assert time.monotonic() - t0 < 10 and "\n" not in str(exc.value)


def test_a_huge_world_argument_is_one_line():
    with pytest.raises(WorldError, match="at most 4,096"):
        load_world("x" * 50_000)


def _world(goal, start=(0.0, 0.0), obstacles=()):
    return parse_world({"robot": {"start": list(start)}, "goal": {"position": list(goal)},
                        "obstacles": list(obstacles)})


def test_worlds_refuse_unreachable_goals_starts_in_obstacles_and_huge_coordinates():
    box = {"kind": "box", "center": [3.0, 0.0], "size": [1.0, 1.0]}
    with pytest.raises(WorldError, match=r"goal \(3, 0\) lies inside obstacles\[0\] \(box\)"):
        check_runnable(_world([3.0, 0.0], obstacles=[box]))
    with pytest.raises(WorldError, match=r"start \(3, 0\) is inside obstacles\[0\]"):
        check_runnable(_world([6.0, 0.0], start=(3.0, 0.0), obstacles=[box]))
    check_runnable(_world([3.0, 0.62], obstacles=[box]))     # beside it: fine
    with pytest.raises(WorldError, match="beyond the 1000 m"):
        _world([1e300, 0.0])
    many = [{"kind": "cylinder", "center": [i * 0.5 - 200.0, 50.0], "radius": 0.1}
            for i in range(2001)]
    check_runnable(_world([5.0, 0.0], obstacles=many))     # no obstacle limit any more
    for name in ("energy", "open", "papf-test-4", "wang-unreachable-goal", "wang-3d-fig9"):
        check_runnable(load_world(name))


def test_a_misspelt_world_name_names_the_world_meant():
    res = papf("run", "--world", "enrgy")
    assert res.returncode == 2
    assert "no packaged world named 'enrgy'; did you mean 'energy'?" in res.stderr


def test_a_broken_world_file_names_line_and_column(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[goal]\nposition = [1, 2]\nname = "x\n')
    res = papf("plan", "--world", str(bad))
    assert res.returncode == 2
    assert "is not valid TOML: line 3, column 10: Illegal character" in res.stderr
    assert "(in 'name = \"x')" in res.stderr
    bad.write_text("[goal]\nposition = [1, 2\n")
    res = papf("plan", "--world", str(bad))
    assert "line 2, at the end of the file: Unclosed array" in res.stderr
