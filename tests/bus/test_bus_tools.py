"""papf topic / goal / teleop over a real router. Every topic tool that would run until Ctrl-C
stops alike on ``--once``, ``--count N`` and ``--duration S``; ``papf topic echo`` under a flood
of large messages keeps its memory bounded and says what it dropped; keys and node names a peer
chose are printed escaped."""

from __future__ import annotations

import io
import math
import os
import subprocess
import threading
import time

import pytest
import zenoh

from common import ros2
from common.errors import ConfigError
from common.transport import zenoh_config
from papf.bus import topics
from papf.bus.goal import send_goal
from papf.bus.teleop import TeleopState
from papf.bus.teleop import run as teleop_run
from schemas import Goal, Keys, PlannerStatus, Scan, Twist
from tests.support.cli import papf

KEYS = Keys("rosbot")


EVIL = "\x1b]0;owned\x07\x1b[2J"




def _scan(stamp: int = 100) -> Scan:
    return Scan(stamp_ns=stamp, angle_min=-math.pi, angle_increment=0.1, range_min=0.2,
                range_max=25.0, ranges=[1.0] * 20)


def test_teleop_needs_a_terminal(session):
    r, w = os.pipe()
    try:
        with pytest.raises(ConfigError, match="terminal"):
            teleop_run(session, KEYS, TeleopState(), fd=r, out=io.StringIO())
    finally:
        os.close(r)
        os.close(w)


def test_teleop_in_a_pty_publishes_the_keys_on_cmd_vel_with_the_clock_stamp(session):
    from schemas import Clock

    got: list[Twist] = []
    sub = session.declare_subscriber(KEYS.cmd_vel,
                                     lambda s: got.append(Twist.from_bytes(s.payload.to_bytes())))
    master, slave = os.openpty()
    out = io.StringIO()
    th = threading.Thread(target=teleop_run, args=(session, KEYS, TeleopState()),
                          kwargs={"fd": slave, "out": out, "period_s": 0.05}, daemon=True)
    th.start()
    try:
        _wait(lambda: got, "first command")
        session.put(KEYS.clock, Clock(stamp_ns=4_200_000_000).to_bytes())
        # the clock arrives on its own callback: keys pressed before it would go out with stamp 0
        _wait(lambda: got[-1].stamp_ns == 4_200_000_000, "a command with the clock's stamp")
        os.write(master, b"ww\x1b[D")
        _wait(lambda: got and (got[-1].v, got[-1].w) == (0.1, 0.2), "v 0.1, w 0.2")
        assert got[-1].stamp_ns == 4_200_000_000
        os.write(master, b"q")
        th.join(30.0)
        assert not th.is_alive()
        _wait(lambda: (got[-1].v, got[-1].w) == (0.0, 0.0), "zero on quit")
        assert "v +0.10 m/s  w +0.20 rad/s" in out.getvalue()
    finally:
        if th.is_alive():     # a failed check: let the teleop quit before its terminal closes
            os.write(master, b"q")
            th.join(30.0)
        sub.undeclare()
        os.close(master)
        os.close(slave)


def _wait(cond, what: str, timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not cond():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


# -- topic and goal over a router ------------------------------------------------------------
def _publish_for(session, seconds: float, stop: threading.Event) -> threading.Thread:
    def loop() -> None:
        i = 0
        t_end = time.monotonic() + seconds
        while not stop.is_set() and time.monotonic() < t_end:
            session.put(KEYS.scan, _scan(i * 100_000_000).to_bytes())
            session.put("odometry/filtered", ros2.encode(
                ros2.odometry(i * 100_000_000, 0.1 * i, 0.0, 0.0, 0.1, 0.0), ros2.ODOMETRY))
            i += 1
            time.sleep(0.05)
    th = threading.Thread(target=loop, daemon=True)
    th.start()
    return th


def test_topic_list_echo_hz_over_the_router(router, session):
    import zenoh

    from common.transport import zenoh_config

    stop = threading.Event()
    th = _publish_for(session, 120.0, stop)   # until stopped; the time only bounds it
    try:
        with zenoh.open(zenoh_config("client", [router])) as s2:
            lines: list[str] = []
            assert topics.topic_list(s2, KEYS, 2.0, lines.append) == 2
            scan_row = next(x for x in lines if x.startswith("rosbot/scan "))
            assert "papf/Scan/v1" in scan_row and "Hz" in scan_row
            assert any(x.startswith("odometry/filtered ") and "nav_msgs/msg/Odometry" in x
                       and "cdr" in x for x in lines)
            assert any(x.startswith("rosbot/goal ") and "silent" in x for x in lines)
            echoed: list[str] = []
            assert topics.echo(s2, "odometry/filtered", echoed.append, count=2) == 2
            assert "[nav_msgs/msg/Odometry, cdr]" in echoed[0] and "frame_id: odom" in echoed[0]
            rates = topics.hz(s2, "rosbot/scan", [].append, duration_s=1.5)
            r = rates["rosbot/scan"].rate()
            # arrivals: about the 20 Hz it is published at (a busy machine delays or bunches
            # them, so only the order of magnitude); stamps: exactly 10 Hz
            assert 2.0 < r.hz < 200.0 and r.stamp_hz == pytest.approx(10.0)
    finally:
        stop.set()
        th.join()


def test_topic_cli_echo_once_and_timeout(router, session):
    stop = threading.Event()
    th = _publish_for(session, 120.0, stop)   # until stopped: three CLI start-ups under load
    try:
        r = papf("topic", "echo", "scan", "--once", "--connect", router, timeout=60)
        assert r.returncode == 0, r.stderr
        assert r.stdout.startswith("# rosbot/scan  [papf/Scan/v1, msgpack]")
        r = papf("topic", "hz", "/odometry/filtered", "--count", "5", "--connect", router,
                 timeout=60)
        assert r.returncode == 0 and "odometry/filtered:" in r.stdout and " Hz (" in r.stdout
        r = papf("topic", "echo", "nothing/here", "--timeout", "0.5", "--connect", router,
                 timeout=60)
        assert r.returncode == 5 and "no message on nothing/here" in r.stderr
    finally:
        stop.set()
        th.join()


def _fake_planner(session, reached_after: int, threads: list[threading.Thread]):
    """Answers a goal with ready, then counts down the distance and reports reached (on a
    thread added to ``threads``: to be joined before the session closes)."""
    goals: list[Goal] = []

    def on_goal(sample) -> None:
        g = Goal.from_bytes(sample.payload.to_bytes())
        goals.append(g)
        session.put(KEYS.planner_status, PlannerStatus(stamp_ns=0, state="ready").to_bytes())
        if len(goals) == 1:
            threads.append(threading.Thread(target=drive, daemon=True))
            threads[-1].start()

    def drive() -> None:
        for i in range(reached_after + 1):
            time.sleep(0.05)
            state = "reached" if i == reached_after else "driving"
            session.put(KEYS.planner_status, PlannerStatus(
                stamp_ns=i, state=state, distance_to_goal=float(reached_after - i)).to_bytes())
    return session.declare_subscriber(KEYS.goal, on_goal), goals


def test_goal_cli_handshake_start_run_and_outcome(router, session):
    from schemas import Event

    events: list[Event] = []
    ev_sub = session.declare_subscriber(KEYS.events,
                                        lambda s: events.append(Event.from_bytes(s.payload.to_bytes())))
    threads: list[threading.Thread] = []
    sub, goals = _fake_planner(session, reached_after=20, threads=threads)
    try:
        r = papf("goal", "3", "-1.5", "--tolerance", "0.2", "--start-run", "--connect", router,
                 timeout=60)
        assert r.returncode == 0, r.stderr
        assert "acknowledged" in r.stdout and r.stdout.rstrip().endswith("reached")
        assert (goals[0].x, goals[0].y, goals[0].tolerance) == (3.0, -1.5, 0.2)
        # run_started comes from the CLI's session, the statuses from ours: no order between them
        _wait(lambda: events, "run_started")
        assert [e.kind for e in events] == ["run_started"]
        assert r.stderr.count("to the goal:") == 11        # piped: one line per 10 %
    finally:
        sub.undeclare()
        ev_sub.undeclare()
        for th in threads:   # done putting before the session closes ("Already borrowed")
            th.join(30)


def test_goal_superseded_by_another_goal_exits_6(router, session):
    import zenoh

    from common.transport import zenoh_config

    timers: list[threading.Timer] = []
    answered = threading.Event()   # the planner's answer to the re-targeting goal is out

    def on_goal(sample) -> None:
        g = Goal.from_bytes(sample.payload.to_bytes())
        session.put(KEYS.planner_status, PlannerStatus(stamp_ns=0, state="ready").to_bytes())
        if g.x == 1.0:   # someone else re-targets the planner right after
            timers.append(threading.Timer(0.3, lambda: session.put(KEYS.goal, Goal(
                stamp_ns=0, x=5.0, y=0.0).to_bytes())))
            timers[-1].start()
        else:
            answered.set()

    sub = session.declare_subscriber(KEYS.goal, on_goal)
    try:
        with zenoh.open(zenoh_config("client", [router])) as s2:
            res = send_goal(s2, KEYS, 1.0, 2.0, out=[].append, timeout_s=20.0)
        assert res.outcome == "superseded" and res.exit_code == 6 and "(5, 0)" in res.reason
    finally:
        # done putting before the session closes: a put in flight on the timer's thread or in
        # the callback (Zenoh's thread) makes the close fail ("Already borrowed")
        for t in list(timers):
            t.join(30)
        if timers:
            answered.wait(10)
        sub.undeclare()


def test_goal_without_a_planner_fails_and_usage_errors_exit_2(session, monkeypatch, router):
    import papf.bus.goal as goal_mod

    monkeypatch.setattr(goal_mod, "HANDSHAKE_S", 1.0)
    res = send_goal(session, KEYS, 1.0, 2.0, out=[].append)
    assert res.outcome == "no_planner" and res.exit_code == 6 and "nodes.planner" in res.reason
    r = papf("goal", "1", "--connect", router, timeout=60)
    assert r.returncode == 2 and "X Y" in r.stderr and "Traceback" not in r.stderr
    from papf.launch.supervisor import free_port

    nobody = f"tcp/127.0.0.1:{free_port()}"
    for cmd in (["goal", "1", "2"], ["topic", "list"], ["teleop"]):
        r = papf(*cmd, "--connect", nobody, timeout=60)
        assert r.returncode == 2 and "cannot reach the bus" in r.stderr, (cmd, r.stderr)
        assert "Traceback" not in r.stderr


def test_tls_without_credentials_names_the_authentication():
    from papf.launch.supervisor import free_port

    r = papf("topic", "list", "--connect", f"tls/127.0.0.1:{free_port()}", timeout=60)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "authenticates its clients" in r.stderr and "--zenoh-config" in r.stderr, r.stderr


def test_echo_under_a_flood_of_large_messages_stays_bounded(router, session):
    """A peer puts 1 MB messages as fast as it can while the printer is stuck, then slow.

    The printer reads nothing until the flood is over (a terminal paging, or a machine too
    busy to print): whatever pace the bus delivers at, more than the bounds arrive unread, so
    the oldest must be dropped and counted, and the queue never holds more than its bounds.
    """
    inbox = topics.Inbox(session, "flood/**", max_items=50, max_bytes=8 * 1024 * 1024)
    peak, arrived = {"items": 0, "bytes": 0}, []
    put = inbox.put

    def watched_put(key, data, arrival):
        put(key, data, arrival)
        arrived.append(len(data))
        peak["items"] = max(peak["items"], len(inbox))
        peak["bytes"] = max(peak["bytes"], inbox._bytes)

    inbox.put = watched_put
    with zenoh.open(zenoh_config("client", [router])) as s:
        payload = b"\x00" * (1024 * 1024)
        for _ in range(300):
            s.put("flood/big", payload)
    deadline = time.monotonic() + 10
    while len(arrived) < 20 and time.monotonic() < deadline:   # the last ones still in flight
        time.sleep(0.05)
    got = 0
    try:
        while inbox.get(0.5) is not None:
            got += 1
            time.sleep(0.02)           # a slow terminal
    finally:
        inbox.close()
    assert len(arrived) >= 20, f"only {len(arrived)} of 300 floods reached the subscriber"
    assert peak["items"] <= 50 and peak["bytes"] <= 8 * 1024 * 1024, peak
    assert inbox.dropped > 0 and got + inbox.dropped == len(arrived), (got, inbox.dropped)


def test_topic_list_shows_a_peers_escape_sequences_never_runs_them(router, session):
    keys = Keys("rosbot")
    lines: list[str] = []
    with zenoh.open(zenoh_config("client", [router])) as s:
        token = s.liveliness().declare_token(keys.alive(f"{EVIL}node"))
        pub_key = f"rosbot/{EVIL}topic"

        def put_some():
            for _ in range(20):
                s.put(pub_key, b"\x80")
                time.sleep(0.02)

        t = threading.Thread(target=put_some, daemon=True)
        t.start()
        topics.topic_list(session, keys, 0.5, lines.append)
        t.join(5)
        token.undeclare()
    text = "\n".join(lines)
    assert "\x1b" not in text and "\x07" not in text
    assert "\\x1b]0;owned" in text      # shown, escaped: the node name and the key


def _topic(*args, router: str) -> subprocess.CompletedProcess:
    return papf("topic", *args, "--connect", router, timeout=90)


@pytest.fixture
def scans(router, session):
    stop = threading.Event()
    th = _publish_for(session, 300.0, stop)   # 20 Hz until stopped
    yield router
    stop.set()
    th.join()


def test_echo_duration_prints_what_came_and_stops(scans):
    t0 = time.monotonic()
    r = _topic("echo", "scan", "--duration", "3", router=scans)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("# rosbot/scan") >= 5           # 20 Hz for 3 s, under any load
    assert time.monotonic() - t0 < 60


def test_echo_duration_with_nothing_published_is_exit_5(router):
    r = _topic("echo", "nothing/here", "--duration", "1", router=router)
    assert r.returncode == 5 and "no message on nothing/here within 1 s" in r.stderr


def test_hz_takes_count_and_once(scans):
    r = _topic("hz", "scan", "--count", "5", router=scans)
    assert r.returncode == 0 and "rosbot/scan" in r.stdout and " Hz (" in r.stdout
    r = _topic("hz", "scan", "--once", router=scans)
    assert r.returncode == 0 and r.stdout.count("rosbot/scan") == 1


def test_pub_takes_count_and_duration(router, session):
    got: list[Twist] = []
    sub = session.declare_subscriber(KEYS.cmd_vel,
                                     lambda s: got.append(Twist.from_bytes(s.payload.to_bytes())))
    try:
        r = _topic("pub", "cmd_vel", "{v: 0.1, w: 0.0}", "--count", "3", "--rate", "20", router=router)
        assert r.returncode == 0, r.stderr
        deadline = time.monotonic() + 10
        while len(got) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(got) == 3 and got[-1].v == pytest.approx(0.1)
        got.clear()
        r = _topic("pub", "cmd_vel", "{v: 0.2, w: 0.0}", "--duration", "1", "--rate", "10", router=router)
        assert r.returncode == 0, r.stderr
        assert 1 <= len(got) <= 11
    finally:
        sub.undeclare()


@pytest.mark.parametrize("tool", [["echo", "scan"], ["hz", "scan"], ["pub", "cmd_vel", "{}"]])
def test_every_tool_has_the_three_stops(tool):
    for flag in ("--once", "--count", "--duration"):
        r = papf("topic", *tool, "--help", timeout=60)
        assert flag in r.stdout, (tool, flag)


def test_topic_list_on_a_narrow_terminal_keeps_every_cell_whole(scans, session):
    """Issue #35, tables that fit: `papf topic list` on a terminal is a table that fits it."""
    import io

    from rich.console import Console

    from papf.bus.topics import topic_list
    from papf.console.tables import print_table

    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=60, color_system=None)
    topic_list(session, KEYS, 1.0, lambda line: out.write(line + "\n"),
               table=lambda t: print_table(t, console))
    text = out.getvalue()
    assert all(len(line) <= 60 for line in text.splitlines())
    assert "KEY: rosbot/scan" in text and "TYPE:     papf/Scan/v1" in text
