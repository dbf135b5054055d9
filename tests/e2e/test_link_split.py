"""`papf run --link`: the robot and the laptop on their own routers, joined through papf link.

A LAN run reaches its goal; a 10 s outage mid-drive (stall: the link holds everything, TCP
resumes at its next retry): the robot brakes within 0.75 s and stands within 1.2 s, obeys
nothing while the link is down, drives on after it and the run ends with an outcome;
Ctrl-C stops every process. The slow links (100 ms ± 50 ms, 200 ms + 0-150 ms) are in
test_link_slow.py.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from common.outcomes import OUTCOMES
from tests.support import warm
from tests.support.cli import stderr_until
from tests.support.e2e import leftovers as _leftovers
from tests.support.link import CORRIDOR, RUN_TIMEOUT_S, split_run
from tests.support.link import commands as _commands
from tests.support.worlds import SHORT, write_world

PY = sys.executable
SLOW = ["--set", "v_max=0.3"]      # the corridor takes ~9 s: an outage at 3 s hits a drive
BRAKING_S = 0.75                   # [s] after the link went: the robot is told to slow down
STANDSTILL_S = 1.2                 # [s] ... and to stand


@pytest.fixture
def corridor(tmp_path) -> Path:
    return write_world(tmp_path / "corridor.toml", CORRIDOR)


def test_a_split_run_over_a_lan_reaches_its_goal(corridor):
    ns = "t30lan"
    code, result, err = split_run(corridor, ns, "lan", "--set", "v_max=0.5")
    assert (code, result["outcome"]) == (0, "reached"), err[-3000:]
    assert result["collisions"] == 0 and result["path_length_m"] > 2.0
    link = result["link_emulator"]
    assert link["spec"]["name"] == "lan" and link["connections"] >= 1
    assert link["directions"]["back"]["bytes"] > 10_000     # scans and odometry came through
    assert link["directions"]["out"]["chunks"] > 0          # commands went
    assert not _leftovers(ns), "processes left after papf run --link"


def test_a_10_s_outage_stops_the_robot_and_the_run_goes_on_after_it(corridor, tmp_path):
    ns, trace = "t30out", tmp_path / "commands.jsonl"
    code, result, err = split_run(corridor, ns, "lan,outage=10@3", *SLOW,
                                  "--robot-trace", str(trace))
    assert result["outcome"] in OUTCOMES, err[-3000:]            # the run ended with an outcome
    assert (code, result["outcome"]) == (0, "reached"), err[-3000:]
    outage = result["link_emulator"]["outages"][0]
    down, up = outage["start_monotonic_ns"], outage["end_monotonic_ns"]
    assert (up - down) / 1e9 == pytest.approx(10.0, abs=0.1)
    cmds = _commands(trace)
    before = [c for c in cmds if c["t_ns"] < down]
    during = [c for c in cmds if down <= c["t_ns"] < up]
    assert before and before[-1]["v"] > 0.2, "the outage did not hit a drive"
    braking = next(c for c in during if c["v"] < before[-1]["v"] - 1e-9)
    standstill = next(c for c in during if c["v"] == 0.0 and c["w"] == 0.0)
    print(f"\noutage: braking after {(braking['t_ns'] - down) / 1e9:.3f} s, standstill after "
          f"{(standstill['t_ns'] - down) / 1e9:.3f} s")
    assert (braking["t_ns"] - down) / 1e9 <= BRAKING_S
    assert (standstill["t_ns"] - down) / 1e9 <= STANDSTILL_S
    obeyed = [c for c in during if c["t_ns"] >= standstill["t_ns"] and (c["v"] or c["w"])]
    assert not obeyed, f"moved while the link was down: {obeyed[:3]}"
    assert any(c["v"] > 0.0 for c in cmds if c["t_ns"] > up), "did not drive on after the outage"
    assert not _leftovers(ns)


def _interrupted_once_driving(argv: list[str]) -> tuple[int, list[str]]:
    """Start ``argv`` (a papf command that makes split runs), SIGINT it once a run drives
    (the link's t0 line); its exit code and the stderr lines read."""
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    seen: list[str] = []
    try:
        stderr_until(proc, r"t0: the outage schedule", seen, timeout_s=180)
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, seen


def test_ctrl_c_stops_every_process_of_both_sides(corridor):
    ns = "t30int"
    code, seen = _interrupted_once_driving([PY, "-m", "papf", "run", "--world", str(corridor),
                                            "--namespace", ns, "--link", "wifi", "--json",
                                            *SLOW])
    assert code == 130, seen[-10:]
    assert not _leftovers(ns), "processes left after Ctrl-C"


def test_the_link_experiment_makes_its_table_and_resumes(tmp_path):
    world = write_world(tmp_path / "short.toml", SHORT)
    out = tmp_path / "exp"
    args = [PY, "-m", "papf", "experiment", "link", "--world", str(world), "--planners", "apf",
            "--links", "lan", "--outage", "none", "--sweep", "none", "--out", str(out),
            "--namespace", "t30exp"]
    first = subprocess.run(args, capture_output=True, text=True, timeout=RUN_TIMEOUT_S)
    assert first.returncode == 0, first.stderr[-3000:]
    assert "| apf | lan | none | reached |" in (out / "link.md").read_text()
    assert "link: 1/1" in first.stderr                       # progress, one line per run
    again = subprocess.run(args, capture_output=True, text=True, timeout=120)
    assert again.returncode == 0 and "1 of 1 runs finished before" in again.stderr
    assert (out / "link.png").is_file() and (out / "link.csv").read_text().count("\n") == 2


def test_papf_link_alone_stops_on_ctrl_c_and_writes_its_stats(tmp_path):
    from papf.launch.supervisor import free_port, wait_port

    port, stats = free_port(), tmp_path / "link.json"
    proc = warm.popen([PY, "-m", "papf", "link", "--listen", f"tcp/127.0.0.1:{port}", "--to",
                       f"tcp/127.0.0.1:{free_port()}", "--profile", "wifi", "--stats", str(stats)],
                      stdout=None, stderr=subprocess.PIPE)
    try:
        assert wait_port(port, 60.0)
        import socket

        with socket.create_connection(("127.0.0.1", port)) as s:   # nothing at --to:
            s.settimeout(30)                                        # reset, as a refused
            try:                                                    # connection would be
                assert s.recv(10) == b""
            except ConnectionResetError:
                pass
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0 and "stopped;" in err and "Traceback" not in err, err
    data = json.loads(stats.read_text())
    assert data["connections"] >= 1 and data["connect_failures"] >= 1   # (wait_port connects too)
    assert data["spec"]["name"] == "wifi"


def test_ctrl_c_stops_the_link_experiment_and_keeps_no_half_run(tmp_path, corridor):
    out = tmp_path / "exp"
    code, seen = _interrupted_once_driving([PY, "-m", "papf", "experiment", "link", "--world",
                                            str(corridor), "--planners", "apf", "--links",
                                            "lan,wifi", "--outage", "none", "--sweep", "none",
                                            "--out", str(out), "--namespace", "t30expint"])
    assert code == 130, seen[-10:]
    assert list((out / "runs").glob("*.json")) == []        # the interrupted run: not kept
    assert not _leftovers("t30expint")
