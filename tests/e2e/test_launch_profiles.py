"""`papf launch`: robot + laptop (and HIL, sim) profiles reach the goal against the ROSbot emulator."""

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

from common.transport import wait_alive, zenoh_config
from papf.launch.supervisor import free_port, wait_port
from schemas import Keys
from tests.support import warm
from tests.support.cli import papf
from tests.support.e2e import leftovers as _leftovers
from tests.support.worlds import FAST, SHORT, write_world

PY = sys.executable


@pytest.fixture
def world(tmp_path) -> str:
    return str(write_world(tmp_path / "short.toml", SHORT))


# -- processes ----------------------------------------------------------------------------------
def split_run(robot_profile: str, laptop_profile: str, world: str, ns: str, emulator_args: list,
              laptop_extra: list | None = None) -> dict:
    """Robot launcher + emulator + laptop launcher; the laptop's JSON summary."""
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    log = Path(world).with_suffix(f".{robot_profile}.log")
    robot = warm.popen([PY, "-m", "papf", "launch", robot_profile, "--listen", endpoint,
                        "--namespace", ns, "--world", world], stdout=subprocess.DEVNULL,
                       stderr=log.open("w"))
    emulator = None
    try:
        assert wait_port(port, 30.0), "the robot's router did not come up"
        emulator = warm.popen([PY, "-m", "papf", "rosbot-emulator", "--connect", endpoint,
                               "--namespace", ns, *emulator_args], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
        laptop = papf("launch", laptop_profile, "--connect", endpoint, "--namespace", ns, "--world",
                      world, "--timeout", "30", "--json", *FAST, *(laptop_extra or []), timeout=120)
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


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_robot_and_laptop_profiles_reach_the_goal(world):
    ns = "t5launch"
    result = split_run("robot", "laptop", world, ns, ["--world", world])
    assert result["outcome"] == "reached", result
    assert result["path_length_m"] > 0.9 and result["charge_mAh"] > 0
    assert not _leftovers(ns), "orphans after the launchers stopped"


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
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


def test_sim_profile_reaches_the_goal(world):
    out = papf("launch", "sim", "--listen", f"tcp/127.0.0.1:{free_port()}", "--namespace", "t5sim",
               "--world", world, "--json", *FAST, timeout=120)
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
    robot = warm.popen([PY, "-m", "papf", "launch", "robot", "--listen", endpoint, "--namespace",
                        ns, *bridged], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    emulator = None
    try:
        assert wait_port(port, 30.0), "the robot's router did not come up"
        emulator = warm.popen([PY, "-m", "papf", "rosbot-emulator", "--connect", endpoint,
                               "--namespace", ns, *bridged], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
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


@pytest.mark.e2e
def test_a_second_launch_in_a_namespace_exits_2_with_one_line(world, tmp_path):
    """A second `papf launch robot` on the host, and a laptop launch joining a network where
    the namespace's planner is alive (another laptop's), are refused before they start."""
    ns, port = "t5twice", free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    robot = warm.popen([PY, "-m", "papf", "launch", "robot", "--listen", endpoint, "--namespace",
                        ns], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    other = None
    try:
        assert wait_port(port, 30.0), "the robot's router did not come up"
        second = papf("launch", "robot", "--namespace", ns, timeout=60)
        assert second.returncode == 2, second.stderr
        assert second.stderr.strip().splitlines() == [second.stderr.strip()]
        assert f"namespace '{ns}' is in use on this host: base_driver, lidar_sim" in second.stderr
        other_host = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}   # another laptop's planner
        other = subprocess.Popen([PY, "-m", "nodes.planner", "--connect", endpoint, "--namespace",
                                  ns, "--realtime"], env=other_host, start_new_session=True,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            assert not wait_alive(session, Keys(ns), ["planner"], 60.0)
        laptop = papf("launch", "laptop", "--connect", endpoint, "--namespace", ns, "--world",
                      world, timeout=60)
        assert laptop.returncode == 2, laptop.stderr
        assert "is in use on the network at" in laptop.stderr and "planner" in laptop.stderr
        assert len(laptop.stderr.strip().splitlines()) == 1, laptop.stderr
    finally:
        for proc in (other, robot):
            if proc is not None and proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
                proc.wait(timeout=30)
    assert not _leftovers(ns)


@pytest.mark.e2e
def test_the_laptop_waits_for_the_robots_odometry_before_the_run_clock_starts(world, tmp_path):
    """A robot whose odometry comes late (bringup, bridge or — in these tests — the emulator
    still starting on a loaded machine) does not eat the run's timeout: the laptop says it
    waits, and the run starts once the robot talks (it used to start at once and time out
    at 0.00 m: 'never drove under load')."""
    ns, port = "t5late", free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    robot = warm.popen([PY, "-m", "papf", "launch", "robot", "--listen", endpoint, "--namespace",
                        ns], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    emulator = laptop = None
    try:
        assert wait_port(port, 30.0), "the robot's router did not come up"
        laptop = warm.popen([PY, "-m", "papf", "launch", "laptop", "--connect", endpoint,
                             "--namespace", ns, "--world", world, "--timeout", "30", "--json",
                             *FAST], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        seen = []
        for line in laptop.stderr:
            seen.append(line)
            if "waiting for the robot's odometry" in line:
                break
        assert seen and "waiting for the robot's odometry" in seen[-1], seen[-10:]
        time.sleep(2.0)                              # the robot is late: the clock must wait
        emulator = warm.popen([PY, "-m", "papf", "rosbot-emulator", "--connect", endpoint,
                               "--namespace", ns, "--world", world], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
        out, err = laptop.communicate(timeout=120)
        result = json.loads(out.strip().splitlines()[-1])
        # reached within --timeout although the robot came late: the wait is not the run's
        assert result["outcome"] == "reached", (result, err[-2000:])
        assert result["path_length_m"] > 0.9
    finally:
        for proc in (laptop, emulator, robot):
            if proc is not None and proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
                proc.wait(timeout=30)
    assert not _leftovers(ns)
