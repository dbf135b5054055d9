"""End to end: `papf run` starts real node processes over a real Zenoh router with real
pybullet physics, and ends on an outcome with every process stopped."""

import json
import os
import signal
import threading
import time

import pytest
import zenoh

from common.transport import zenoh_config
from papf.launch.supervisor import free_port, wait_port
from schemas import Clock, Keys
from tests.support.e2e import assert_no_orphans, papf_run, pids_of, start_papf_run
from tests.support.worlds import STEADY


def test_open_world_reaches_goal_in_a_straight_line():
    port = free_port()
    code, res, err = papf_run("--world", "open", "--planner", "apf", "--seed", "1", port=port)
    assert res is not None, err
    assert (code, res["outcome"]) == (0, "reached"), err
    assert res["world"] == "open" and res["planner"] == "apf" and res["seed"] == 1
    assert 4.85 <= res["path_length_m"] <= 5.3  # straight line 5 m, goal tolerance 0.1 m
    assert res["charge_mAh"] > 0 and res["energy_J"] > 0 and res["collisions"] == 0
    assert res["sim_time_s"] >= res["duration_s"] > 0  # sim-time figures, not wall time
    assert set(res) >= {"outcome", "planner", "world", "seed", "duration_s", "path_length_m",
                        "charge_mAh", "energy_J", "collisions", "sim_time_s", "wall_time_s"}
    assert_no_orphans(port)


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_same_seed_identical_other_seed_differs():
    runs = [papf_run("--world", "energy", "--planner", "apf", "--seed", str(s), "--timeout", "20",
                     *STEADY) for s in (5, 5, 6)]
    a, b, c = (r[1] for r in runs)
    assert a is not None and b is not None and c is not None, [r[2][-2000:] for r in runs]
    for r in (a, b, c):
        r.pop("wall_time_s")
        r.pop("run_id")   # a fresh id per run, by design (common.seal)
    assert a == b
    assert a != c


def test_timeout_outcome_and_exit_code():
    code, res, err = papf_run("--world", "energy", "--planner", "apf", "--timeout", "3")
    assert (code, res["outcome"], res["sim_time_s"]) == (5, "timeout", 3.0), err


def test_every_nodes_last_line_comes_before_the_launcher_exits():
    # python -m papf run skips the interpreter's teardown (exit_fast) once the supervisor has
    # printed every child's output to its end: the nodes' closing lines are all there
    code, res, err = papf_run("--world", "energy", "--planner", "apf", "--timeout", "0.3", "--verbose")
    assert (code, res["outcome"]) == (5, "timeout"), err
    for node, last in (("lidar_sim", "published"), ("energy_meter", "stopped:"),
                       ("base_driver", "run stopped"), ("planner", "stopping after")):
        assert any(line.startswith(f"[{node}]") and last in line for line in err.splitlines()), err


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_killing_the_planner_stops_the_robot_and_fails_the_run():
    port = free_port()
    proc = start_papf_run("--world", "open", "--planner", "apf", port=port)
    try:
        assert wait_port(port, 60), "the run's router never came up"
        with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as s:
            moving = threading.Event()
            sub = s.declare_subscriber(Keys().clock, lambda smp: Clock.from_bytes(
                smp.payload.to_bytes()).stamp_ns > 3e9 and moving.set())
            assert moving.wait(120), "the run never got to 3 s of sim time"
            sub.undeclare()
            for pid in pids_of("nodes.planner", port):
                os.kill(pid, signal.SIGKILL)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    res = json.loads(out.strip().splitlines()[-1])
    assert proc.returncode == 6 and res["outcome"] == "failed", err
    assert "planner" in res["reason"]
    # the driver's watchdog zeroed the command within 0.5 s (sim) of the last command
    assert res["stop_latency_s"] is not None and res["stop_latency_s"] <= 0.5 + 0.021
    assert_no_orphans(port)


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_garbage_on_cmd_vel_and_scan_crashes_nothing():
    port = free_port()
    proc = start_papf_run("--world", "open", "--planner", "apf", port=port)
    stop = threading.Event()

    def spam():
        with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as s:
            k = Keys()
            junk = [b"", b"\xff\x00garbage", b"\x81\xa5_type\xadpapf/Twist/v1", b"\x93\x01\x02\x03"]
            i = 0
            while not stop.is_set():
                for key in (k.cmd_vel, k.scan, k.odom, k.goal):
                    s.put(key, junk[i % len(junk)])
                i += 1
                time.sleep(0.005)

    t = threading.Thread(target=spam, daemon=True)
    assert wait_port(port, 60), "the run's router never came up"
    t.start()
    try:
        out, err = proc.communicate(timeout=200)
    finally:
        stop.set()
        t.join(30)          # its session closed before the next test
        if proc.poll() is None:
            proc.kill()
    res = json.loads(out.strip().splitlines()[-1])
    assert proc.returncode == 0 and res["outcome"] == "reached", err[-3000:]
    assert_no_orphans(port)


def _ignore_sigint() -> None:   # what a shell does to `papf run … &` in a script
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("sig, ignored_at_start", [(signal.SIGINT, False), (signal.SIGTERM, False),
                                                   (signal.SIGINT, True)])
def test_interrupting_the_launcher_stops_everything(sig, ignored_at_start):
    port = free_port()
    proc = start_papf_run("--world", "energy", "--planner", "apf", port=port,
                          preexec_fn=_ignore_sigint if ignored_at_start else None)
    try:
        assert wait_port(port, 60), "the run's router never came up"
        deadline = time.monotonic() + 60
        while not pids_of("nodes.world_sim", port) and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(1.0)
        os.kill(proc.pid, sig)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err[-2000:]
    assert "interrupted" in err
    assert_no_orphans(port)
