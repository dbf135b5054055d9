"""A fleet's pure parts: several robots in one driver core, the LiDAR's other bodies, the
per-robot processes of a launch, the separation and the fleet's figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.lidar_sim.__main__ import BodyPairs
from nodes.lidar_sim.core import LidarParams, LidarSim
from nodes.world_sim.core import WorldCore
from nodes.world_sim.physics import SimBase
from papf.launch.fleet import FleetMeter, fleet_result
from papf.launch.outcome import RunMonitor
from papf.launch.profile import LaunchOptions, load_profile, resolve
from papf.launch.run import _alive_groups
from schemas.messages import Bodies, Odometry, People, PlannerStatus, Twist
from worlds import parse_world

S = 1_000_000_000  # ns per s


def fleet_world(r2_start=(3.0, 0.0, math.pi), r2_planner=None):
    r2 = {"name": "r2", "start": list(r2_start), "goal": [0.0, 0.0]}
    if r2_planner:
        r2["planner"] = r2_planner
    return parse_world({"name": "f", "robots": [
        {"name": "r1", "start": [0.0, 0.0, 0.0], "goal": [3.0, 0.0]}, r2]})


def answer(core: WorldCore, *robots: str) -> list[bool]:
    return [core.command(Twist(stamp_ns=core.t_ns, v=0.3, w=0.0), r) for r in robots]


def test_lockstep_needs_every_robots_answer():
    with WorldCore(fleet_world(), seed=0) as core:
        out = core.outputs()
        topics = [t for t, _ in out]
        assert topics[:5] == ["r1/sim/bodies", "r1/sim/pose", "r1/odom", "r1/wheels", "r1/clock"]
        assert topics[5:10] == ["r2/sim/bodies", "r2/sim/pose", "r2/odom", "r2/wheels", "r2/clock"]
        bodies = dict(out)["r1/sim/bodies"]
        assert bodies.robots == ("r2",) and bodies.robot_x[0] == pytest.approx(3.0, abs=0.05)
        assert answer(core, "r1") == [False]           # r2 has not answered: not complete
        assert answer(core, "nobody") == [False]       # no such robot: ignored
        assert answer(core, "r2") == [True]
        core.advance()
        assert [t for t, _ in core.outputs()][0] == "r1/sim/pose"   # no scan: no bodies


def test_first_robot_of_a_fleet_starts_as_a_lone_robot():
    """Robot 0 takes the first draws of the seed's rng, as a single robot does."""
    lone = parse_world({"name": "t", "robot": {"start": [0.0, 0.0, 0.0]},
                        "goal": {"position": [3.0, 0.0]}})
    with SimBase(lone, seed=7) as one, SimBase(lone, seed=7, starts=[(0, 0, 0), (3, 0, 0)]) as two:
        assert one.pose() == pytest.approx(two.pose(0), abs=1e-6)
        assert two.pose(1)[0] == pytest.approx(3.0, abs=0.05)


def test_robots_driving_into_each_other_collide_both():
    with WorldCore(fleet_world(r2_start=(0.6, 0.0, math.pi)), seed=0) as core:
        events = []
        while core.t_ns < 3 * S and not events:
            out = core.outputs()
            events += [(t, m) for t, m in out if t.endswith("events") and m.kind == "collision"]
            if core.is_scan_instant():
                answer(core, "r1", "r2")
            core.advance()
        events += [(t, m) for t, m in core.outputs() if t.endswith("events")]
    where = {t: m.detail for t, m in events}
    assert where == {"r1/events": "robot r2", "r2/events": "robot r1"}
    assert core.collision_counts == [1, 1]


def test_lidar_sees_another_robot():
    with LidarSim(parse_world({"name": "e", "robot": {"start": [0, 0, 0]},
                               "goal": {"position": [5, 0]}}),
                  LidarParams(beams=360, noise_sd=0.0)) as lidar:
        assert np.isinf(lidar.true_ranges(0.0, 0.0, 0.0)).all()
        lidar.place_bodies(Bodies(stamp_ns=0, robots=("r2",), robot_x=(2.0,), robot_y=(0.0,),
                                  robot_yaw=(0.0,), person_x=(0.0,), person_y=(-1.5,),
                                  person_radius=(0.3,)))
        ranges = lidar.true_ranges(0.0, 0.0, 0.0)
        ahead, right = ranges[180], ranges[90]           # beam i at -pi + i deg
        assert ahead == pytest.approx(2.0 - 0.1 - lidar.params.sensor_x, abs=1e-3)
        assert right == pytest.approx(1.5 - 0.3, abs=1e-2)
        lidar.place_bodies(Bodies(stamp_ns=1))              # gone: nothing seen
        assert np.isinf(lidar.true_ranges(0.0, 0.0, 0.0)).all()


def test_scan_waits_for_pose_and_bodies_in_either_order():
    pairs = BodyPairs()
    pose, bodies = Odometry(stamp_ns=100, x=0, y=0, yaw=0, v=0, w=0), Bodies(stamp_ns=100)
    assert pairs.add("sim/pose", pose) == (None, None)
    assert pairs.add("sim/bodies", bodies) == (pose, bodies)
    assert pairs.add("sim/bodies", Bodies(stamp_ns=200)) == (None, None)
    later = Odometry(stamp_ns=200, x=1, y=0, yaw=0, v=0, w=0)
    assert pairs.add("sim/pose", later) == (later, Bodies(stamp_ns=200))


def test_launch_gives_each_robot_its_nodes_and_planner(tmp_path):
    path = tmp_path / "f.toml"
    path.write_text('name = "f"\n[[robots]]\nname = "r1"\nstart = [0, 0]\ngoal = [3, 0]\n'
                    '[[robots]]\nname = "r2"\nstart = [3, 1]\ngoal = [0, 1]\nplanner = "papf"\n')
    graph = resolve(load_profile("sim"), LaunchOptions("sim", values={"world": str(path),
                                                                       "planner": "apf"}))
    nodes = graph.nodes
    # the LiDARs and the meters serve every robot from one process each (fleet = "one"); the
    # planners differ, so each robot has its own
    assert {"r1/planner", "r2/planner", "lidar_sim", "energy_meter", "base_driver"} == set(nodes)

    def arg(name, flag):
        argv = nodes[name]
        return argv[argv.index(flag) + 1]
    assert (arg("r1/planner", "--planner"), arg("r2/planner", "--planner")) == ("apf", "papf")
    assert (arg("r1/planner", "--namespace"), arg("r2/planner", "--namespace")) == ("r1", "r2")
    assert arg("lidar_sim", "--robots") == arg("energy_meter", "--robots") == "r1,r2"
    assert _alive_groups(nodes) == {"rosbot": ["energy_meter", "lidar_sim", "base_driver"],
                                    "r1": ["energy_meter", "planner", "lidar_sim"],
                                    "r2": ["energy_meter", "planner", "lidar_sim"]}


def test_robots_with_one_planner_share_its_process(tmp_path):
    """Robots whose planners are alike (the same algorithm and settings) are planned for by
    one process (fleet = "one"): each still has its planner's token on its namespace."""
    path = tmp_path / "f.toml"
    path.write_text('name = "f"\n[[robots]]\nname = "r1"\nstart = [0, 0]\ngoal = [3, 0]\n'
                    '[[robots]]\nname = "r2"\nstart = [3, 1]\ngoal = [0, 1]\n')
    nodes = resolve(load_profile("sim"), LaunchOptions("sim", values={"world": str(path),
                                                                       "planner": "papf"})).nodes
    assert {"planner", "lidar_sim", "energy_meter", "base_driver"} == set(nodes)
    argv = nodes["planner"]
    assert argv[argv.index("--robots") + 1] == "r1,r2" and argv[argv.index("--planner") + 1] == "papf"
    assert _alive_groups(nodes)["r2"] == ["energy_meter", "planner", "lidar_sim"]


def test_a_fleet_node_whose_robots_differ_runs_per_robot(tmp_path):
    """Without the passing layer only the IAPF robot's LiDAR gives ground-truth tracks:
    the LiDARs' arguments differ, so each robot gets its own (the meters still agree)."""
    path = tmp_path / "f.toml"
    path.write_text('name = "f"\n[[robots]]\nname = "r1"\nstart = [0, 0]\ngoal = [3, 0]\n'
                    '[[robots]]\nname = "r2"\nstart = [3, 1]\ngoal = [0, 1]\nplanner = "iapf"\n')
    nodes = resolve(load_profile("sim"), LaunchOptions(
        "sim", values={"world": str(path), "planner": "apf", "passing": "off"})).nodes
    assert {"r1/lidar_sim", "r2/lidar_sim", "energy_meter"} <= set(nodes) and "lidar_sim" not in nodes
    assert "--truth-objects" in nodes["r2/lidar_sim"] and "--truth-objects" not in nodes["r1/lidar_sim"]
    assert "--robots" not in nodes["r1/lidar_sim"]


def test_a_profile_names_how_a_node_serves_a_fleet(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text('name = "p"\n[[nodes]]\nname = "lidar_sim"\nmodule = "nodes.lidar_sim"\n'
                    'fleet = "shared"\n')
    with pytest.raises(ConfigError, match="fleet must be one of each, one"):
        load_profile(str(path))


def pose(t, x, y=0.0, yaw=0.0):
    return Odometry(stamp_ns=t, x=x, y=y, yaw=yaw, v=0.0, w=0.0)


def test_separation_is_taken_up_to_each_robots_end():
    meter = FleetMeter(["r1", "r2"], {}, people=False, period_ns=10)
    for t, x2 in ((0, 2.0), (10, 1.0), (15, 0.1), (20, 0.5)):   # 15: between samples
        meter.on_pose("r2", pose(t, x2))       # either robot first: measured once both came
        meter.on_pose("r1", pose(t, 0.0))
    assert meter.at("r1", 10) == (pytest.approx(0.8), 0.0)   # footprints 0.2 m long
    assert meter.at("r2", 25)[0] == pytest.approx(0.3)
    assert meter.at("r1", -1) == (math.inf, 0.0)


def test_people_bring_separation_and_discomfort():
    meter = FleetMeter(["r1"], {}, people=True)
    for t, px in ((0, 2.0), (S, 0.35), (2 * S, 0.3)):    # a person 0.3 m wide comes near
        meter.on_people(People(stamp_ns=t, x=(px,), y=(0.0,), vx=(0.0,), vy=(0.0,),
                               radius=(0.1,)))
        meter.on_pose("r1", pose(t, 0.0))
    sep, discomfort = meter.at("r1", 2 * S)
    assert sep == pytest.approx(0.1) and discomfort == pytest.approx(2.0)
    assert meter.at("r1", 0) == (pytest.approx(1.8), 0.0)


def monitor(outcome: str, t_ns: int) -> RunMonitor:
    m = RunMonitor(10.0)
    m.on_pose(Odometry(stamp_ns=0, x=0, y=0, yaw=0, v=0.5, w=0))
    m.on_status(PlannerStatus(stamp_ns=t_ns, state=outcome))
    return m


def test_fleet_outcome_is_the_worst_robots():
    sep = FleetMeter(["r1", "r2"], {}, people=False)
    both = fleet_result([("r1", "apf", monitor("reached", 2 * S)),
                         ("r2", "apf", monitor("reached", 3 * S))], sep, "f", 0, 1.0)
    assert (both.outcome, both.duration_s, both.planner) == ("reached", 3.0, "apf")
    d = both.to_json()
    assert [r["name"] for r in d["robots"]] == ["r1", "r2"] and d["min_separation_m"] is None
    mixed = fleet_result([("r1", "apf", monitor("reached", 2 * S)),
                          ("r2", "papf", monitor("stagnated", 3 * S))], sep, "f", 0, 1.0)
    assert (mixed.outcome, mixed.exit_code, mixed.planner) == ("stagnated", 3, "apf+papf")
    assert mixed.reason.startswith("r2: stagnated")


def test_single_robot_json_has_no_fleet_fields():
    d = monitor("reached", S).result("apf", "w", 0, 1.0).to_json()
    assert not {"robots", "min_separation_m", "discomfort_s"} & set(d)


def people_world(person: dict):
    return parse_world({"name": "p", "robot": {"start": [0.0, 0.0, 0.0]},
                        "goal": {"position": [3.0, 0.0]}, "people": [person]})


def test_people_walk_in_the_driver_and_the_lidar_is_told():
    with WorldCore(people_world({"start": [2.0, 1.0], "goal": [-2.0, 1.0]}), seed=0) as core:
        first = core.outputs()
        assert [t for t, _ in first][:3] == ["sim/people", "sim/bodies", "sim/pose"]
        assert dict(first)["sim/bodies"].person_x == (2.0,)
        while core.t_ns < S:
            core.advance()
        people = dict(core.outputs())["sim/people"]
    assert people.x[0] == pytest.approx(1.0, abs=0.1) and people.vx[0] < -0.9   # 1 m/s


def test_driving_into_a_person_is_a_collision():
    slow = {"start": [0.6, 0.0], "goal": [0.6, 0.0], "speed": 0.05}   # cannot get away
    with WorldCore(people_world(slow), seed=0) as core:
        collisions = []
        while core.t_ns < 3 * S and not collisions:
            if core.is_scan_instant():
                core.command(Twist(stamp_ns=core.t_ns, v=0.4, w=0.0))
            core.advance()
            collisions += [m for t, m in core.outputs() if t == "events" and m.kind == "collision"]
    assert [c.detail for c in collisions] == ["person 0, caused by the robot"]


def test_a_robots_unknown_planner_is_refused_before_anything_starts():
    from common.errors import ConfigError
    from papf.launch.preflight import check_run

    with pytest.raises(ConfigError, match="robot 'r2'.*did you mean 'papf'"):
        check_run(fleet_world(r2_planner="papff"), "apf", 0, 60.0, None, "rosbot", None, [])


def test_join_needs_a_router_and_a_valid_endpoint():
    from common.errors import ConfigError
    from papf.launch.preflight import check_launch

    with pytest.raises(ConfigError, match="runs no router"):
        check_launch(LaunchOptions("laptop", connect=["tcp/127.0.0.1:7447"],
                                   join=["tcp/10.0.0.2:7447"]), load_profile("laptop"))
    with pytest.raises(ConfigError, match="--join"):
        check_launch(LaunchOptions("robot", join=["tcp/nowhere"]), load_profile("robot"))
    robot = LaunchOptions("robot", listen=["tcp/127.0.0.1:7450"], join=["tcp/10.0.0.2:7447"])
    check_launch(robot, load_profile("robot"))
    router = resolve(load_profile("robot"), robot).processes[0].argv
    assert router[router.index("--join") + 1] == "tcp/10.0.0.2:7447"


def test_a_fleet_recordings_track_keeps_its_robot_and_shows_the_others(tmp_path):
    from nodes.recorder.writer import RunWriter
    from papf.recording.track import load_track

    path = tmp_path / "fleet.mcap"
    with RunWriter(path, {"world": "energy", "planner": "apf", "namespace": "r1"}) as w:
        for k in range(5):
            t = k * 20_000_000
            w.write_message("r1/sim/pose", pose(t, 0.1 * k))
            w.write_message("r2/sim/pose", pose(t, 5.0 - 0.1 * k, 1.0, math.pi))
            w.write_message("r1/sim/people", People(stamp_ns=t, x=(2.0,), y=(float(k),),
                                                    vx=(0.0,), vy=(1.0,), radius=(0.3,)))
    track = load_track(path)
    assert track.xyyaw[:, 0].tolist() == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    assert list(track.others) == ["r2"] and track.others["r2"][1][-1, 0] == pytest.approx(4.6)
    assert [xy[0, 1] for xy in track.people_xy] == [0.0, 1.0, 2.0, 3.0, 4.0]
    assert track.people_r.tolist() == [0.3]
    assert load_track(path, robot="r2").xyyaw[0, 0] == pytest.approx(5.0)


def test_a_fleet_recordings_report_has_a_run_per_robot(tmp_path):
    from nodes.recorder.writer import RunWriter
    from papf.report.report import collect
    from schemas.messages import BatteryState, Event

    path = tmp_path / "fleet.mcap"
    with RunWriter(path, {"world": "energy", "planner": "apf", "namespace": "r1",
                          "seed": "0"}) as w:
        for ns in ("r1", "r2"):
            w.write_message(f"{ns}/events", Event(stamp_ns=0, kind="run_started", source="t"))
        for k in range(51):
            t = k * 20_000_000
            for ns, speed in (("r1", 0.5), ("r2", 0.25)):
                odom = Odometry(stamp_ns=t, x=speed * k * 0.02, y=0.0, yaw=0.0, v=speed, w=0.0)
                w.write_message(f"{ns}/sim/pose", odom)
                w.write_message(f"{ns}/odom", odom)
                w.write_message(f"{ns}/battery", BatteryState(
                    stamp_ns=t, voltage=11.1, current=1.0, power=11.1,
                    charge_used_mAh=0.01 * k, energy_J=0.1 * k, model="motor"))
            if k == 50:
                for ns in ("r1", "r2"):
                    w.write_message(f"{ns}/planner/status",
                                    PlannerStatus(stamp_ns=t, state="reached"))
    runs = collect([path])
    assert [r.file for r in runs] == ["fleet.mcap:r1", "fleet.mcap:r2"]
    assert [round(r.path_length_m, 3) for r in runs] == [0.5, 0.25]


def test_the_viewer_shows_the_other_robots_and_the_people():
    from nodes.viewer.core import ViewCore

    out = ViewCore().on_message("sim/bodies", Bodies(
        stamp_ns=5, robots=("r2",), robot_x=(1.0,), robot_y=(2.0,), robot_yaw=(0.5,),
        person_x=(3.0,), person_y=(4.0,), person_radius=(0.3,)))
    [(channel, scene, t)] = out
    [ent] = scene["entities"]
    assert (channel, t, ent["id"]) == ("/fleet", 5, "fleet")
    assert [c["pose"]["position"]["x"] for c in ent["cubes"]] == [1.0]
    assert [t["text"] for t in ent["texts"]] == ["r2"]
    assert [c["size"]["x"] for c in ent["cylinders"]] == [pytest.approx(0.6)]


def test_each_robots_lidar_noise_is_its_own():
    w = parse_world({"name": "e", "robot": {"start": [0, 0, 0]}, "goal": {"position": [5, 0]},
                     "obstacles": [{"kind": "box", "center": [2.0, 0.0], "size": [0.5, 4.0]}]})
    scans = []
    for robot in (0, 0, 1):
        with LidarSim(w, LidarParams(beams=90), seed=3, robot=robot) as lidar:
            scans.append(lidar.scan(0.0, 0.0, 0.0, 100_000_000).ranges)
    assert np.array_equal(scans[0], scans[1]) and not np.array_equal(scans[0], scans[2])
    with LidarSim(w, LidarParams(beams=90), seed=3) as lone:   # robot 0 = a lone robot
        assert np.array_equal(lone.scan(0.0, 0.0, 0.0, 100_000_000).ranges, scans[0])


def test_progress_names_each_robot_or_counts_them():
    from papf.launch.fleet import progress_figures

    two = {"r1": monitor("reached", S), "r2": RunMonitor(10.0)}
    two["r2"].on_pose(pose(S, 1.0))
    t, far, _, state = progress_figures(two, {"r1": (0.0, 0.0), "r2": (4.0, 0.0)})
    assert (far, state) == (3.0, "r1 reached | r2 3.0 m")
    many = {f"r{i}": RunMonitor(10.0) for i in range(6)}
    assert progress_figures(many, {n: (0.0, 0.0) for n in many})[3] == "0/6 done"


def test_papf_launch_refuses_a_fleet_world_papf_run_drives_it():
    from common.errors import ConfigError
    from papf.launch.preflight import check_launch

    with pytest.raises(ConfigError, match="papf run drives a fleet"):
        check_launch(LaunchOptions("sim", values={"world": "fleet-corridor-swap"}),
                     load_profile("sim"))
