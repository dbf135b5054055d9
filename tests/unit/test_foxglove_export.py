"""``papf export foxglove`` and ``papf animate`` on a recording, and the planner's run-time
parameters. The export is read back with the stock ``mcap`` reader and every message is
validated against its channel's schema — which must be Foxglove's own."""

from __future__ import annotations

import json
import math

import jsonschema
import numpy as np
import pytest
from mcap.reader import make_reader

from nodes.planner.params import answer
from nodes.planner.registry import make_planner
from nodes.recorder.writer import RunWriter
from nodes.viewer.core import CHANNELS, schema_json
from papf.cli import main as papf_main
from schemas.messages import (
    BatteryState,
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
from tests.support.worlds import traffic_world

NS = 1_000_000_000


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A 3 s recorded run on papf-test-4: poses/odom/battery at 50 Hz, the rest at 10 Hz."""
    path = tmp_path_factory.mktemp("rec") / "run.mcap"
    with RunWriter(path, {"world": "papf-test-4", "planner": "papf", "seed": 0}) as w:
        w.write_message("rosbot/goal", Goal(stamp_ns=0, x=2.2, y=2.7))
        for k in range(150):
            t = k * 20_000_000
            x = 0.1 * t / NS
            pose = Odometry(stamp_ns=t, x=x, y=0.0, yaw=0.0, v=0.1, w=0.0)
            w.write_message("rosbot/sim/pose", pose)
            w.write_message("rosbot/odom", pose)
            w.write_message("rosbot/battery", BatteryState(
                stamp_ns=t, voltage=12.0, current=1.0, power=12.0, charge_used_mAh=t / NS,
                energy_J=12 * t / NS))
            if k % 5 == 0:
                ranges = np.where(np.arange(300) % 3, 1.5, np.inf).astype(np.float32)
                w.write_message("rosbot/scan", Scan(
                    stamp_ns=t, angle_min=-math.pi, angle_increment=2 * math.pi / 300,
                    range_min=0.2, range_max=25.0, ranges=ranges))
                w.write_message("rosbot/cmd_vel", Twist(stamp_ns=t, v=0.1, w=0.0))
                w.write_message("rosbot/objects", Objects(stamp_ns=t, source="truth", tracks=(
                    ObjectTrack(id=1, x=2.0 - x, y=0.0, vx=-0.1, length=0.4, width=0.3),)))
                w.write_message("rosbot/planner/state", PlannerState(
                    stamp_ns=t, algorithm="papf", force=(1.0, 0.0),
                    predicted_path=((x, 0.0), (x + 1, 0.5)),
                    debug=planner_debug("papf", top_quarks=[(0.5, 0.9)]),
                    temporary_goal=(x + 1, 0.5)))
                w.write_message("rosbot/planner/status", PlannerStatus(stamp_ns=t,
                                                                       state="driving"))
        w.write_message("rosbot/events", Event(stamp_ns=3 * NS, kind="run_ended",
                                               source="launcher", detail="{}"))
        w.write("rosbot/not_a_topic", b"\x01\x02")
    return path


def test_export_reads_back_and_validates(recording, tmp_path):
    out = tmp_path / "fox.mcap"
    assert papf_main(["export", "foxglove", str(recording), str(out)]) == 0
    want = {c.topic: c.schema for c in CHANNELS}
    counts: dict[str, int] = {}
    validators = {}
    with open(out, "rb") as f:
        reader = make_reader(f)
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        assert meta["run"]["world"] == "papf-test-4"
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema.name == want[channel.topic]
            assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
            if schema.id not in validators:   # each schema checked once, not per message
                declared = json.loads(schema.data)
                assert declared == schema_json(schema.name)
                cls = jsonschema.validators.validator_for(declared)
                cls.check_schema(declared)
                validators[schema.id] = cls(declared)
            validators[schema.id].validate(json.loads(message.data))
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    assert set(counts) == set(want) - {"/fleet"}   # every channel (a lone robot: no fleet)
    assert counts["/scan"] == 30 and counts["/robot/pose"] == 150 and counts["/battery"] == 150
    assert counts["/world"] >= 2 * 3            # world + footprint, every second of log time


def test_export_errors(recording, tmp_path, capsys):
    assert papf_main(["export", "foxglove", str(recording), str(recording)]) == 2
    assert papf_main(["export", "foxglove", str(tmp_path / "none.mcap"),
                      str(tmp_path / "o.mcap")]) == 2
    assert papf_main(["export", "foxglove", str(recording), str(tmp_path / "o.mcap"),
                      "--world", "no-such-world"]) == 2
    err = capsys.readouterr().err
    assert "no packaged world" in err and "Traceback" not in err


def test_animate_gif(recording, tmp_path):
    from PIL import Image

    out = tmp_path / "run.gif"
    assert papf_main(["animate", str(recording), str(out), "--speed", "1", "--fps", "2"]) == 0
    with Image.open(out) as im:
        assert im.n_frames == 7   # 0 .. 2.98 s every 0.5 s, and the last pose
    assert papf_main(["animate", str(recording), str(tmp_path / "run.avi")]) == 2


def test_planner_params_listed_set_and_refused():
    planner = make_planner("papf")
    reply, changed = answer("papf", planner, b"")
    assert reply["error"] == "" and changed == [] and reply["params"]["apf.v_max"] == 0.1
    reply, changed = answer("papf", planner, json.dumps(
        {"set": ["apf.v_max=0.3", "papf.max_quarks=4"]}).encode())
    assert reply["error"] == "" and sorted(changed) == ["apf.v_max", "papf.max_quarks"]
    assert planner.apf.v_max == 0.3 and planner.strategy.params.max_quarks == 4
    before = dict(reply["params"])
    for bad in (["apf.v_max=fast"], ["apf.v_max=0.2", "nonsense=1"], "v_max=1"):
        reply, changed = answer("papf", planner, json.dumps({"set": bad}).encode())
        assert reply["error"] and changed == [] and reply["params"] == before
    reply, _ = answer("papf", planner, b"\xff")
    assert reply["error"]


def test_launch_and_run_start_the_viewer_with_their_goal_policy(capsys):
    from papf.launch.run import RunConfig, resolve_run

    def goals(argv):   # argparse: the last --goals wins
        return [argv[i + 1] for i, a in enumerate(argv) if a == "--goals"][-1]

    assert papf_main(["launch", "laptop", "--connect", "tcp/127.0.0.1:1", "--world", "open",
                      "--view", "8799", "--dry-run"]) == 0
    procs = json.loads(capsys.readouterr().out)["processes"]
    viewer = [p["argv"] for p in procs if p["name"] == "viewer"]
    assert len(viewer) == 1 and goals(viewer[0]) == "accept" and "8799" in viewer[0]
    lockstep = resolve_run(RunConfig(world="open", view=8765)).nodes["viewer"]
    realtime = resolve_run(RunConfig(world="open", view=8765, realtime=True)).nodes["viewer"]
    assert goals(lockstep) == "refuse" and goals(realtime) == "accept"
    assert "viewer" not in resolve_run(RunConfig(world="open")).nodes


TRAFFIC_TOML = traffic_world(goal_x=6.0)


def test_traffic_world_export_and_animation(tmp_path):
    """Moving obstacles where they are (export: entity ``moving`` per scan; GIF: drawn)."""
    from PIL import Image

    world = tmp_path / "traffic.toml"
    world.write_text(TRAFFIC_TOML)
    rec = tmp_path / "t.mcap"
    with RunWriter(rec, {"world": str(world), "planner": "iapf"}) as w:
        for k in range(101):
            t = k * 20_000_000
            w.write_message("rosbot/sim/pose", Odometry(stamp_ns=t, x=0.01 * k, y=0.0, yaw=0.0,
                                                        v=0.5, w=0.0))
            if k % 5 == 0:
                w.write_message("rosbot/scan", Scan(
                    stamp_ns=t, angle_min=0.0, angle_increment=0.1, range_min=0.2,
                    range_max=25.0, ranges=np.ones(3, dtype=np.float32)))
    out = tmp_path / "t-fox.mcap"
    assert papf_main(["export", "foxglove", str(rec), str(out)]) == 0
    xs = []
    with open(out, "rb") as f:
        for _s, _channel, message in make_reader(f).iter_messages(topics=["/world"]):
            for ent in json.loads(message.data)["entities"]:
                if ent["id"] == "moving":
                    xs.append(ent["cubes"][0]["pose"]["position"]["x"])
    assert len(xs) == 21 and xs[0] == pytest.approx(3.0) and xs[-1] == pytest.approx(3.2)
    gif = tmp_path / "t.gif"
    assert papf_main(["animate", str(rec), str(gif), "--speed", "1", "--fps", "2"]) == 0
    with Image.open(gif) as im:
        assert im.n_frames == 5
