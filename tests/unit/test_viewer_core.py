"""The viewer's pure core: every Foxglove message it makes validates against Foxglove's
JSON Schema (vendored from @foxglove/schemas), with the geometry the stack meant."""

from __future__ import annotations

import json
import math

import jsonschema
import numpy as np
import pytest

from common.optional import tomllib
from nodes.viewer import convert as cv
from nodes.viewer.core import CHANNELS, ViewCore, goal_from_client, param_sets, schema_json
from nodes.viewer.scene import footprint_scene, mind_scene, moving_scene, world_scene
from schemas.messages import (
    BatteryState,
    Event,
    Goal,
    Odometry,
    PlannerState,
    PlannerStatus,
    Scan,
    Twist,
)
from tests.support.messages import planner_debug
from tests.support.worlds import traffic_world
from worlds import load_world, packaged_worlds, parse_world

SCHEMAS = {c.topic: schema_json(c.schema) for c in CHANNELS}
TRAFFIC = parse_world(tomllib.loads(traffic_world(extra="""[[obstacles]]
kind = "cylinder"
center = [6.0, 2.0]
radius = 0.3
""")))


def valid(topic: str, payload: dict) -> dict:
    """Validate as Foxglove would parse it (strict JSON: no NaN or infinity)."""
    parsed = json.loads(json.dumps(payload, allow_nan=False))
    jsonschema.validate(parsed, SCHEMAS[topic])
    return parsed


def test_schemas_are_foxgloves_own():
    for spec in CHANNELS:
        schema = schema_json(spec.schema)
        if spec.schema.startswith("foxglove."):
            assert schema["title"] == spec.schema
            assert "foxglove-sdk" in schema["$comment"]
        jsonschema.Draft202012Validator.check_schema(schema)


def test_scan_no_return_and_angles():
    ranges = np.array([1.0, np.inf, np.nan, 2.0], dtype=np.float32)
    scan = Scan(stamp_ns=1_500_000_001, angle_min=-math.pi, angle_increment=math.pi / 2,
                range_min=0.2, range_max=25.0, ranges=ranges, sensor_x=0.02, sensor_yaw=0.1)
    out = valid("/scan", cv.laser_scan(scan))
    assert out["timestamp"] == {"sec": 1, "nsec": 500_000_001}
    assert out["ranges"] == [1.0, cv.NO_RETURN_M, cv.NO_RETURN_M, 2.0]
    assert out["end_angle"] == pytest.approx(-math.pi + 1.5 * math.pi)
    tf = valid("/tf", cv.laser_transforms(scan))["transforms"][0]
    assert (tf["parent_frame_id"], tf["child_frame_id"]) == ("base_link", "laser")
    assert tf["translation"]["x"] == pytest.approx(0.02)
    assert 2 * math.atan2(tf["rotation"]["z"], tf["rotation"]["w"]) == pytest.approx(0.1)


def test_pose_source_prefers_ground_truth():
    core = ViewCore()
    odom = Odometry(stamp_ns=0, x=1.0, y=0.0, yaw=0.0, v=0.0, w=0.0)
    truth = Odometry(stamp_ns=0, x=1.1, y=0.0, yaw=0.0, v=0.0, w=0.0)
    assert [t for t, _, _ in core.on_message("odom", odom)] == ["/odom", "/tf", "/robot/pose"]
    core.on_message("sim/pose", truth)
    assert [t for t, _, _ in core.on_message("odom", odom)] == ["/odom"]
    assert core.robot_xy == (1.1, 0.0)


@pytest.mark.parametrize("name", [w for w in packaged_worlds() if load_world(w).dims == 2][:4]
                         + ["wang-3d-fig9"])
def test_world_scenes_valid(name):
    world = load_world(name)
    ent = valid("/world", world_scene(world))["entities"][0]
    n = len(ent["cubes"]) + len(ent["cylinders"]) + len(ent["spheres"])
    assert n == len(world.obstacles) + 1   # + the goal disc
    valid("/world", footprint_scene(5))


def test_road_and_moving_obstacles():
    ent = valid("/world", world_scene(TRAFFIC))["entities"][0]
    assert len(ent["cubes"]) == 0 and len(ent["cylinders"]) == 2   # the static one + goal disc
    ys = sorted({p["points"][0]["y"] for p in ent["lines"]})
    assert ys == pytest.approx([-0.3, 0.3, 0.9])
    dashed = [p for p in ent["lines"] if p["type"] == cv.LINE_LIST]
    assert len(dashed) == 1 and len(dashed[0]["points"]) % 2 == 0
    moving = valid("/world", moving_scene(TRAFFIC, 10_000_000_000))["entities"][0]
    assert moving["id"] == "moving" and moving["cubes"][0]["pose"]["position"]["x"] == 4.0
    core = ViewCore(TRAFFIC)
    scan = Scan(stamp_ns=0, angle_min=0.0, angle_increment=0.1, range_min=0.2, range_max=25.0,
                ranges=np.ones(3, dtype=np.float32))
    assert "/world" in [t for t, _, _ in core.on_message("scan", scan)]


def test_mind_scene_draws_every_part():
    state = PlannerState(stamp_ns=7, algorithm="papf", mode="bypass", force=(3.0, -4.0),
                         temporary_goal=(1.0, 2.0), predicted_path=((0, 0), (1, 1), (2, 1)),
                         debug=planner_debug("papf", abandoned_paths=[[(0, 0), (0, 1)], [(0, 0), (1, -1)]],
                                             top_quarks=[(0.5, 0.5), (0.7, 0.2)])
                         + planner_debug("arapf", virtual_walls=[[(3, 0), (3, 1)]],
                                         virtual_obstacles=[(4.0, 4.0)]))
    ent = valid("/planner/scene", mind_scene(state, (0.0, 0.0)))["entities"][0]
    assert len(ent["lines"]) == 4            # 2 abandoned + prediction + 1 wall
    assert len(ent["spheres"]) == 4          # 2 quarks + 1 virtual obstacle + temporary goal
    assert ent["arrows"][0]["pose"]["orientation"]["z"] == pytest.approx(
        math.sin(math.atan2(-4.0, 3.0) / 2))
    assert ent["texts"][0]["text"] == "papf: bypass"
    quark = next(sp for sp in ent["spheres"] if sp["pose"]["position"]["x"] == 0.5)
    style = state.value("top_quarks")     # the plug-in's declared style
    assert quark["size"]["x"] == style.size and quark["color"]["r"] == style.colour[0]
    iapf = PlannerState(stamp_ns=7, algorithm="iapf", mode="lane-goal",
                        debug=planner_debug("iapf", lane_goal_y=0.75, local_minimum_count=3))
    words = valid("/planner/scene", mind_scene(iapf, (0.0, 0.0)))["entities"][0]["texts"][0]
    assert words["text"] == "iapf: lane-goal · local minima ahead 3 · lane goal y 0.75 m"
    empty = valid("/planner/scene", mind_scene(PlannerState(stamp_ns=0, algorithm="apf")))
    assert empty["entities"][0]["arrows"] == [] and empty["entities"][0]["lines"] == []


def test_logs_and_plots_valid():
    ev = Event(stamp_ns=3, kind="collision", source="base_driver", x=1.0, y=2.0)
    log = valid("/log", cv.event_log(ev))
    assert log["level"] == cv.LOG_WARNING and "(1.00, 2.00)" in log["message"]
    assert valid("/log", cv.event_log(Event(stamp_ns=3, kind="info", source="x")))["level"] == 2
    status = valid("/planner/status", cv.plot_dict(PlannerStatus(stamp_ns=1, state="idle")))
    assert status["distance_to_goal"] is None   # nan -> null
    valid("/battery", cv.plot_dict(BatteryState(stamp_ns=1, voltage=12.0, current=1.0, power=12.0,
                                                charge_used_mAh=0.1, energy_J=1.0)))
    valid("/cmd_vel", cv.plot_dict(Twist(stamp_ns=1, v=0.1, w=0.0)))
    valid("/goal", cv.goal_pose(Goal(stamp_ns=1, x=1.0, y=2.0)))


def test_repeat_and_static_outputs():
    core = ViewCore(load_world("energy"), repeat_ns=1_000_000_000)
    first = core.on_message("goal", Goal(stamp_ns=0, x=1.0, y=1.0))
    assert [t for t, _, _ in first] == ["/world", "/world", "/goal", "/goal"]
    pose = Odometry(stamp_ns=500_000_000, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0)
    assert "/world" not in [t for t, _, _ in core.on_message("odom", pose)]
    later = Odometry(stamp_ns=1_000_000_000, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0)
    assert "/world" in [t for t, _, _ in core.on_message("odom", later)]
    assert ViewCore().on_message("wheels", object()) == []


@pytest.mark.parametrize("payload, xy", [
    ({"header": {}, "pose": {"position": {"x": 1, "y": 2.5, "z": 0}}}, (1.0, 2.5)),
    ({"header": {}, "point": {"x": -1, "y": 0, "z": 0}}, (-1.0, 0.0)),
    ({"pose": {"pose": {"position": {"x": 3, "y": 4}}}}, (3.0, 4.0)),
    ({"x": 0.5, "y": 0.25}, (0.5, 0.25)),
    ({"pose": {"position": {"x": "a", "y": 2}}}, None),
    ({"x": True, "y": 1}, None),
    ([1, 2], None),
])
def test_goal_from_client(payload, xy):
    assert goal_from_client(json.dumps(payload).encode()) == xy


def test_goal_from_client_garbage():
    assert goal_from_client(b"\xff\x00") is None
    assert goal_from_client(b"not json") is None


def test_param_sets():
    assert param_sets({"apf.v_max": 0.3, "papf.use_numba": False, "papf.max_quarks": 3}) == [
        "apf.v_max=0.3", "papf.use_numba=false", "papf.max_quarks=3"]


def test_committed_layout_is_the_generated_one():
    from pathlib import Path

    from nodes.viewer.core import GOAL_TOPICS
    from nodes.viewer.layout import GOAL_PUBLISH_TOPIC, layout_json

    text = (Path(__file__).resolve().parents[2] / "docs" / "foxglove-layout.json").read_text()
    assert text == layout_json(), "regenerate: papf view --layout docs/foxglove-layout.json"
    assert GOAL_PUBLISH_TOPIC in GOAL_TOPICS
    topics = {c.topic for c in CHANNELS}
    for path in ("/cmd_vel.v", "/battery.charge_used_mAh", "/planner/status.distance_to_goal"):
        assert path.rsplit(".", 1)[0] in topics and path in text


def test_objects_scene():
    from schemas.messages import Objects, ObjectTrack

    msg = Objects(stamp_ns=5, source="tracker", tracks=(
        ObjectTrack(id=3, x=1.0, y=2.0, yaw=0.5, vx=0.5, vy=0.0, length=0.5, width=0.3),
        ObjectTrack(id=4, x=0.0, y=0.0)))
    out = ViewCore().on_message("objects", msg)
    assert [t for t, _, _ in out] == ["/objects"]
    ent = valid("/objects", out[0][1])["entities"][0]
    assert len(ent["cubes"]) == 2 and len(ent["arrows"]) == 1
    assert ent["cubes"][0]["size"]["x"] == 0.5 and ent["texts"][0]["text"] == "tracker 3"


def test_view_layout_refuses_an_existing_file_and_follows_no_symlink(tmp_path, capsys):
    from papf.cli import main

    target = tmp_path / "user.json"
    target.write_text("mine")
    link = tmp_path / "layout.json"
    link.symlink_to(target)
    assert main(["view", "--layout", str(link)]) == 2
    assert "already exists" in capsys.readouterr().err
    assert main(["view", "--layout", str(link), "--force"]) == 0
    assert target.read_text() == "mine" and not link.is_symlink()


@pytest.mark.parametrize("host,goals,params,ok", [
    ("127.0.0.1", "accept", "accept", True), ("localhost", "accept", "accept", True),
    ("::1", "accept", "accept", True), ("0.0.0.0", "accept", "accept", False),
    ("0.0.0.0", "refuse", "accept", False), ("192.168.1.5", "accept", "refuse", False),
    ("robot.lan", "refuse", "refuse", True), ("0.0.0.0", "refuse", "refuse", True)])
def test_the_viewer_steers_only_from_this_host(host, goals, params, ok):
    from common.errors import ConfigError
    from nodes.viewer.__main__ import check_exposure, parse_args

    args = parse_args(["--host", host, "--goals", goals, "--params", params])
    if ok:
        check_exposure(args)
    else:
        with pytest.raises(ConfigError, match="no authentication"):
            check_exposure(args)
