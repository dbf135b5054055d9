"""The viewer node through the Foxglove WebSocket protocol, as Foxglove's app speaks it.

A router, the viewer node and a planner node run as processes; the test publishes the
stack's messages on Zenoh and is a Foxglove client: it sees the channels advertised with
their schema names, subscribes, and validates every message it receives against the
channel's JSON Schema (Foxglove's own for ``foxglove.*``). Goals and parameters go the
other way, through the protocol.
"""

from __future__ import annotations

import json
import sys
import time

import jsonschema
import numpy as np
import pytest

from bench.foxglove_ws import FoxgloveClient
from common.transport import wait_alive
from nodes.viewer.core import CHANNELS, schema_json
from papf.launch.supervisor import free_port
from schemas import Keys
from schemas.messages import (
    BatteryState,
    Bodies,
    Event,
    Goal,
    Objects,
    ObjectTrack,
    Odometry,
    PlannerState,
    PlannerStatus,
    Scan,
    Twist,
)
from tests.support.messages import planner_debug

KEYS = Keys("rosbot")


def _start_viewer(spawn, router, *extra) -> str:
    port = free_port()
    spawn("viewer", [sys.executable, "-m", "nodes.viewer", "--connect", router, "--port",
                     str(port), "--world", "papf-test-4", *extra])
    return f"ws://127.0.0.1:{port}"


def _stack_messages(t_ns: int):
    ranges = np.full(300, np.inf, dtype=np.float32)
    ranges[:50] = 2.5
    ranges[60] = np.nan
    pose = Odometry(stamp_ns=t_ns, x=1.0, y=0.5, yaw=0.2, v=0.1, w=0.0)
    return [
        ("sim/pose", pose), ("odom", pose),
        ("scan", Scan(stamp_ns=t_ns, angle_min=-np.pi, angle_increment=2 * np.pi / 300,
                      range_min=0.2, range_max=25.0, ranges=ranges, sensor_x=0.02)),
        ("goal", Goal(stamp_ns=t_ns, x=4.0, y=4.0)),
        ("planner/state", PlannerState(
            stamp_ns=t_ns, algorithm="papf", mode="drive", force=(1.0, 0.5),
            temporary_goal=(2.0, 2.0), predicted_path=((1.0, 0.5), (1.5, 0.8), (2.0, 1.2)),
            debug=planner_debug("papf", abandoned_paths=[[(1.0, 0.5), (0.5, 1.5)]],
                                top_quarks=[(1.8, 1.0)])
            + planner_debug("arapf", virtual_walls=[[(0.0, 2.0), (1.0, 2.0)]],
                            virtual_obstacles=[(0.5, 2.0)]))),
        ("planner/status", PlannerStatus(stamp_ns=t_ns, state="driving", distance_to_goal=4.0)),
        ("cmd_vel", Twist(stamp_ns=t_ns, v=0.1, w=0.05)),
        ("battery", BatteryState(stamp_ns=t_ns, voltage=12.1, current=0.8, power=9.7,
                                 charge_used_mAh=0.2, energy_J=1.5)),
        ("events", Event(stamp_ns=t_ns, kind="info", source="test", detail="hello")),
        ("objects", Objects(stamp_ns=t_ns, source="truth", tracks=(
            ObjectTrack(id=1, x=3.0, y=0.0, vx=0.5, length=0.5, width=0.3),))),
        ("sim/bodies", Bodies(stamp_ns=t_ns, robots=("r2",), robot_x=(2.0,), robot_y=(1.0,),
                              robot_yaw=(0.3,), person_x=(3.0,), person_y=(2.0,),
                              person_radius=(0.3,))),
    ]


def test_channels_advertised_subscribed_and_valid(router, spawn, session):
    url = _start_viewer(spawn, router, "--goals", "refuse")
    client = FoxgloveClient(url, timeout_s=30.0)
    try:
        want = {c.topic: c.schema for c in CHANNELS}
        assert client.wait_for(lambda: set(want) <= set(client.topics()), 30.0), client.topics()
        for topic, ch in client.topics().items():
            assert ch["schemaName"] == want[topic]
            assert ch["encoding"] == "json" and ch["schemaEncoding"] == "jsonschema"
            assert json.loads(ch["schema"]) == schema_json(want[topic])
        client.subscribe(set(want))
        client.pump(0.5)
        t, deadline = 0, time.monotonic() + 60      # until every channel has a message
        while not client.wait_for(lambda: set(want) <= set(client.messages), 0.2) and \
                time.monotonic() < deadline:
            t += 1
            for topic, msg in _stack_messages(t * 100_000_000):
                session.put(KEYS.key(topic), msg.to_bytes())
        assert set(want) <= set(client.messages), sorted(set(want) - set(client.messages))
        for topic, received in client.messages.items():
            schema = schema_json(want[topic])
            for _log_time, payload, _ in received:
                jsonschema.validate(json.loads(payload), schema)
        scan = json.loads(client.messages["/scan"][-1][1])
        assert scan["frame_id"] == "laser" and len(scan["ranges"]) == 300
        assert scan["ranges"][0] == pytest.approx(2.5) and scan["ranges"][100] == 0.0
        frames = {(tf["parent_frame_id"], tf["child_frame_id"])
                  for _, p, _ in client.messages["/tf"] for tf in json.loads(p)["transforms"]}
        assert frames == {("world", "base_link"), ("base_link", "laser")}
        mind = json.loads(client.messages["/planner/scene"][-1][1])["entities"][0]
        assert len(mind["lines"]) == 3 and len(mind["spheres"]) == 3 and len(mind["arrows"]) == 1
        # a goal from the 3D panel is refused (lockstep run), with a log line
        client.advertise(7, "/goal_pose", "geometry_msgs/msg/PoseStamped")
        client.pump(0.3)
        client.publish(7, {"header": {"frame_id": "world"},
                           "pose": {"position": {"x": 3.0, "y": -1.0, "z": 0.0},
                                    "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}})
        assert client.wait_for(lambda: any(b"refused" in p for _, p, _ in client.messages["/log"]))
    finally:
        client.close()


def test_goal_from_the_3d_panel_is_published(router, spawn, session):
    got = []
    sub = session.declare_subscriber(KEYS.goal, lambda s: got.append(
        Goal.from_bytes(s.payload.to_bytes())))
    url = _start_viewer(spawn, router, "--goals", "accept")
    client = FoxgloveClient(url, timeout_s=30.0)
    try:
        assert client.wait_for(lambda: "/log" in client.topics(), 30.0)
        client.advertise(3, "/clicked_point", "geometry_msgs/msg/PointStamped")
        client.pump(0.3)
        client.publish(3, {"header": {"frame_id": "world"}, "point": {"x": 2.5, "y": 1.5, "z": 0}})
        client.wait_for(lambda: bool(got), 30.0)
        assert [(g.x, g.y) for g in got] == [(2.5, 1.5)]
    finally:
        client.close()
        sub.undeclare()


def test_parameters_listed_and_set_through_validation(router, spawn, session):
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", "papf", "--connect",
                      router])
    assert not wait_alive(session, KEYS, ["planner"], 60.0)
    url = _start_viewer(spawn, router)
    client = FoxgloveClient(url, timeout_s=30.0)
    try:
        def params(names=()):
            return client.request({"op": "getParameters", "parameterNames": list(names)},
                                  "parameterValues", 30.0)
        assert client.wait_for(lambda: "/log" in client.topics(), 30.0)
        client.subscribe({"/log"})
        listed = params()
        values = {p["name"]: p["value"] for p in listed["parameters"]}
        assert values["apf.v_max"] == pytest.approx(0.1) and "papf.max_quarks" in values
        ok = client.request({"op": "setParameters",
                             "parameters": [{"name": "apf.v_max", "value": 0.25}]},
                            "parameterValues")
        assert {p["name"]: p["value"] for p in ok["parameters"]} == {"apf.v_max": 0.25}
        assert {p["name"]: p["value"] for p in params(["apf.v_max"])["parameters"]} == {
            "apf.v_max": 0.25}
        bad = client.request({"op": "setParameters",
                              "parameters": [{"name": "papf.max_quarks", "value": "many"}]},
                             "parameterValues")
        assert {p["name"]: p["value"] for p in bad["parameters"]} == {
            "papf.max_quarks": values["papf.max_quarks"]}
        assert client.wait_for(lambda: any(b"refused" in p and b"max_quarks" in p
                                           for _, p, _ in client.messages["/log"]), 10.0)
    finally:
        client.close()


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_papf_run_realtime_view_serves_every_channel(tmp_path):
    """The acceptance case, shortened: `papf run --realtime --view PORT` while a client watches."""
    import subprocess

    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "papf", "run", "--world", "open", "--planner",
                             "papf", "--realtime", "--view", str(port), "--timeout", "12",
                             "--json", "--port", str(free_port())],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        client = FoxgloveClient(f"ws://127.0.0.1:{port}", timeout_s=60.0)
        # events come when they happen; obstacle tracks only with --objects truth|tracker;
        # other robots and people only in a fleet or a world with people
        want = {c.topic for c in CHANNELS} - {"/log", "/objects", "/fleet"}
        assert client.wait_for(lambda: want <= set(client.topics()), 60.0)
        client.subscribe(want)
        client.wait_for(lambda: want <= set(client.messages), 20.0)
        client.close()
        assert want <= set(client.messages), sorted(want - set(client.messages))
        out, err = proc.communicate(timeout=120)
        assert json.loads(out)["outcome"] == "timeout", err[-2000:]
    finally:
        proc.kill()
        proc.wait()


def test_replay_view_serves_a_recording(router, tmp_path):
    """`papf replay FILE --view PORT`: the recording's messages reach a Foxglove client."""
    import signal
    import subprocess

    from nodes.recorder.writer import RunWriter

    rec = tmp_path / "r.mcap"
    with RunWriter(rec, {"world": "papf-test-4"}) as w:   # 30 s: it outlasts the client's start
        for k in range(1500):
            w.write_message("rosbot/odom", Odometry(stamp_ns=k * 20_000_000, x=0.01 * k, y=0.0,
                                                    yaw=0.0, v=0.5, w=0.0))
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "papf", "replay", str(rec), "--rate", "1",
                             "--connect", router, "--view", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        client = FoxgloveClient(f"ws://127.0.0.1:{port}", timeout_s=60.0)
        assert client.wait_for(lambda: "/odom" in client.topics(), 30.0)
        client.subscribe({"/odom", "/robot/pose", "/world"})
        assert client.wait_for(lambda: len(client.messages["/odom"]) >= 10, 30.0)
        assert client.wait_for(lambda: bool(client.messages["/world"]), 30.0)   # sent every second
        client.close()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
        assert proc.returncode in (0, 130), err[-2000:]
    finally:
        proc.kill()
        proc.wait()
