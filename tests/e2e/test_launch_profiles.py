"""`papf launch`: the packaged profiles, and robot + laptop against the ROSbot emulator."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zenoh

from common.errors import ConfigError
from common.transport import wait_alive, zenoh_config
from papf.launch.profile import (
    LaunchOptions,
    load_profile,
    local_endpoint,
    packaged_profiles,
    resolve,
)
from papf.launch.supervisor import free_port, wait_port
from schemas import Keys

PY = sys.executable
WORLD = """name = "short"
description = "1.2 m ahead, a box beside the path"
[robot]
start = [0.0, 0.0, 0.0]
[goal]
position = [1.2, 0.0]
tolerance = 0.15
[[obstacles]]
kind = "box"
center = [0.6, 0.6]
size = [0.3, 0.3]
"""
FAST = ["--set", "v_max=0.5"]    # the paper's 0.1 m/s would make a 12 s test


@pytest.fixture
def world(tmp_path) -> str:
    path = tmp_path / "short.toml"
    path.write_text(WORLD)
    return str(path)


def plan(prof, opt):
    graph = resolve(prof, opt)
    return graph.nodes, graph.connect


# -- profiles as data ---------------------------------------------------------------------------
def test_packaged_profiles_load():
    assert {"sim", "robot", "laptop", "hil-robot", "hil-laptop"} <= set(packaged_profiles())
    for name in packaged_profiles():
        prof = load_profile(name)
        assert prof.nodes and prof.name == name
        assert prof.router or prof.run                 # a host either serves or drives
    assert [load_profile(n).router for n in ("robot", "hil-robot", "laptop", "hil-laptop")] == \
        [True, True, False, False]


def test_robot_profile_plan():
    prof = load_profile("robot")
    cmds, connect = plan(prof, LaunchOptions("robot", values={"bridge_namespace": "r1"}))
    assert list(cmds) == ["base_driver", "lidar_sim"] and connect == ["tcp/127.0.0.1:7447"]
    drv = cmds["base_driver"]
    assert drv[1:3] == ["-m", "nodes.base_driver"] and "--world" not in drv
    assert drv[drv.index("--driver") + 1] == "rosbot" and "--realtime" in drv
    assert drv[drv.index("--bridge-namespace") + 1] == "r1"
    assert cmds["lidar_sim"][cmds["lidar_sim"].index("--source") + 1] == "ros2"
    cmds, _ = plan(prof, LaunchOptions("robot", values={"world": "open"}))
    assert cmds["base_driver"][cmds["base_driver"].index("--world") + 1].endswith("open.toml")


def test_laptop_profile_plan_and_errors(world):
    prof = load_profile("laptop")
    opt = LaunchOptions("laptop", connect=["tcp/10.0.0.2:7447"], namespace="r7",
                        values={"world": world, "record": "/tmp/x.mcap"}, planner_args=FAST)
    cmds, connect = plan(prof, opt)
    assert list(cmds) == ["recorder", "energy_meter", "planner"] and connect == opt.connect
    assert cmds["planner"][-4:] == ["--connect", "tcp/10.0.0.2:7447", "--namespace", "r7"]
    assert "--realtime" in cmds["planner"] and "v_max=0.5" in cmds["planner"]
    assert cmds["energy_meter"][cmds["energy_meter"].index("--model") + 1] == "paper"
    assert "recorder" not in plan(prof, LaunchOptions("laptop", connect=["tcp/h:1"]))[0]
    with pytest.raises(ConfigError, match="give --connect"):
        plan(prof, LaunchOptions("laptop"))
    with pytest.raises(ConfigError, match="needs --world"):
        plan(load_profile("hil-laptop"), LaunchOptions("hil-laptop", connect=["tcp/h:1"]))
    with pytest.raises(ConfigError, match="no launch profile 'nope'"):
        load_profile("nope")


def test_bad_profile_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[[nodes]]\nmodule = "x"\n')
    with pytest.raises(ConfigError, match="invalid: KeyError"):
        load_profile(str(bad))
    bad.write_text('router = true\n[[nodes]]\nname = "a"\nmodule = "x"\n')
    with pytest.raises(ConfigError, match="needs listen endpoints"):
        load_profile(str(bad))


def test_local_endpoint():
    assert local_endpoint("tcp/0.0.0.0:7447") == "tcp/127.0.0.1:7447"
    assert local_endpoint("tcp/[::]:7447") == "tcp/127.0.0.1:7447"
    assert local_endpoint("tcp/10.231.0.1:7447") == "tcp/10.231.0.1:7447"


def test_dry_run_prints_the_process_list():
    out = json.loads(subprocess.run([PY, "-m", "papf", "launch", "hil-robot", "--dry-run",
                                     "--listen", "tcp/127.0.0.1:1"], capture_output=True,
                                    text=True, timeout=60, check=True).stdout)
    router, driver = out["processes"]
    assert out["profile"] == "hil-robot" and router["host"] == driver["host"] == "robot"
    assert router["argv"][1:] == ["-m", "papf.launch.router", "--listen", "tcp/127.0.0.1:1"]
    assert driver["argv"][1:5] == ["-m", "nodes.base_driver", "--driver", "rosbot"]


def test_papf_run_and_launch_sim_dry_runs_print_the_same_processes(tmp_path):
    args = ["--world", "energy", "--planner", "papf", "--seed", "3", "--set", "v_max=0.2",
            "--record", str(tmp_path / "r.mcap"), "--energy-model", "paper"]
    run = subprocess.run([PY, "-m", "papf", "run", *args, "--dry-run"], capture_output=True,
                         text=True, timeout=60, check=True).stdout
    launch = subprocess.run([PY, "-m", "papf", "launch", "sim", *args, "--dry-run"],
                            capture_output=True, text=True, timeout=60, check=True).stdout
    assert run == launch
    procs = {p["name"]: p["argv"] for p in json.loads(run)["processes"]}
    assert list(procs) == ["router", "recorder", "energy_meter", "planner", "lidar_sim",
                           "base_driver"]
    rec = procs["recorder"]
    meta = dict(rec[i + 1].split("=", 1) for i, a in enumerate(rec) if a == "--meta")
    assert meta == {"profile": "sim", "world": "energy", "planner": "papf", "seed": "3",
                    "planner_args": "--set v_max=0.2", "energy_model": "paper", "timeout_s": "300"}


# -- processes ----------------------------------------------------------------------------------
def _running(tag: str) -> list[str]:
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if tag in cmd and int(pid) != os.getpid():
            found.append(cmd)
    return found


def _leftovers(tag: str, timeout_s: float = 30.0) -> list[str]:
    """Processes whose command line contains ``tag`` (our unique namespace) still running
    after ``timeout_s`` (a process being stopped may take a moment to go)."""
    deadline = time.monotonic() + timeout_s
    while (found := _running(tag)) and time.monotonic() < deadline:
        time.sleep(0.1)
    return found


def split_run(robot_profile: str, laptop_profile: str, world: str, ns: str, emulator_args: list,
              laptop_extra: list | None = None) -> dict:
    """Robot launcher + emulator + laptop launcher; the laptop's JSON summary."""
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    log = Path(world).with_suffix(f".{robot_profile}.log")
    robot = subprocess.Popen([PY, "-m", "papf", "launch", robot_profile, "--listen",
                              endpoint, "--namespace", ns, "--world", world],
                             start_new_session=True, stdout=subprocess.DEVNULL,
                             stderr=log.open("w"))
    emulator = None
    try:
        assert wait_port(port, 30.0), "the robot's router did not come up"
        emulator = subprocess.Popen([PY, "-m", "papf", "rosbot-emulator", "--connect", endpoint,
                                     "--namespace", ns, *emulator_args], start_new_session=True,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        laptop = subprocess.run([PY, "-m", "papf", "launch", laptop_profile,
                                 "--connect", endpoint, "--namespace", ns, "--world", world,
                                 "--timeout", "30", "--json", *FAST, *(laptop_extra or [])],
                                capture_output=True, text=True, timeout=120)
        assert laptop.stdout.strip(), laptop.stderr[-2000:]
        return json.loads(laptop.stdout.strip().splitlines()[-1])
    finally:
        for proc in (emulator, robot):
            if proc is not None and proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
        try:
            assert robot.wait(timeout=20) == 0, log.read_text()[-2000:]
        finally:
            for proc in (emulator, robot):
                if proc is not None and proc.poll() is None:
                    os.killpg(proc.pid, signal.SIGKILL)
            for proc in (emulator, robot):   # gone before the test looks for leftovers
                if proc is not None:
                    proc.wait(timeout=30)


@pytest.mark.e2e
def test_robot_and_laptop_profiles_reach_the_goal(world):
    ns = "t5launch"
    result = split_run("robot", "laptop", world, ns, ["--world", world])
    assert result["outcome"] == "reached", result
    assert result["path_length_m"] > 0.9 and result["charge_mAh"] > 0
    assert not _leftovers(ns), "orphans after the launchers stopped"


@pytest.mark.e2e
def test_hil_profiles_reach_the_goal(world, tmp_path):
    ns = "t5hil"
    record = tmp_path / "hil.mcap"
    result = split_run("hil-robot", "hil-laptop", world, ns, [],   # the real room is empty
                       ["--record", str(record)])
    assert result["outcome"] == "reached", result
    from papf.recording.reader import open_recording

    with open_recording(record) as rec:
        counts = rec.counts()
    assert counts[f"{ns}/scan"] > 5 and counts[f"{ns}/odom"] > 50
    assert not _leftovers(ns)


@pytest.mark.e2e
def test_sim_profile_reaches_the_goal(world):
    out = subprocess.run([PY, "-m", "papf", "launch", "sim", "--listen",
                          f"tcp/127.0.0.1:{free_port()}", "--namespace", "t5sim", "--world", world,
                          "--json", *FAST], capture_output=True, text=True, timeout=120)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert (result["outcome"], out.returncode) == ("reached", 0), out.stderr[-2000:]
    assert not _leftovers("t5sim")


@pytest.mark.e2e
@pytest.mark.parametrize("bridge", ["", "bot"])
def test_ctrl_c_on_the_robot_profile_stops_without_a_traceback(tmp_path, bridge):
    """Ctrl-C (SIGINT to the foreground process group) on `papf launch robot`, with and
    without a bridge namespace, against the emulator: every node stops, no traceback."""
    ns, port = f"t5stop{bridge}", free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    bridged = ["--bridge-namespace", bridge] if bridge else []
    robot = subprocess.Popen([PY, "-m", "papf", "launch", "robot", "--listen", endpoint,
                              "--namespace", ns, *bridged], start_new_session=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    emulator = None
    try:
        assert wait_port(port, 30.0), "the robot's router did not come up"
        emulator = subprocess.Popen([PY, "-m", "papf", "rosbot-emulator", "--connect", endpoint,
                                     "--namespace", ns, *bridged], start_new_session=True,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            assert not wait_alive(session, Keys(ns), ["base_driver", "lidar_sim"], 60.0)
        time.sleep(1.0)                           # battery and odometry flowing to the driver
        os.killpg(robot.pid, signal.SIGINT)
        _, err = robot.communicate(timeout=60)
    finally:
        for proc in (emulator, robot):
            if proc is not None and proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(timeout=30)
    assert robot.returncode in (0, 130), err[-2000:]
    assert "Traceback" not in err and "Error" not in err, err[-3000:]
    assert not _leftovers(ns)
