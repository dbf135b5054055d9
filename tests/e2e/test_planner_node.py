"""The planner node process answering goal and scan over a router."""

import json
import os
import queue
import subprocess
import sys

import pytest

from bench.foxglove_ws import FoxgloveClient
from common import runauth, seal
from common.transport import attachment_of, wait_alive
from papf.launch.supervisor import free_port
from schemas import Keys
from schemas.messages import (
    Goal,
    PlannerState,
    PlannerStatus,
    Twist,
)
from tests.support import warm
from tests.support.messages import odom, scan

MS = 1_000_000


KEYS = Keys("rosbot")


def _take(inbox: queue.Queue, n: int, after: str, timeout_s: float = 30.0) -> list:
    """``n`` samples from ``inbox``; a failure names the step and what did come."""
    got = []
    try:
        while len(got) < n:
            got.append(inbox.get(timeout=timeout_s))
    except queue.Empty:
        pytest.fail(f"after {after}: {len(got)} of {n} samples within {timeout_s:g} s: "
                    f"{[k for k, _ in got]}")
    return got


@pytest.mark.parametrize("algorithm", ["apf", "papf"])
def test_node_answers_goal_and_scan_over_zenoh(router, spawn, session, algorithm):
    keys = Keys(f"plnode_{algorithm}")
    # subscribed before the planner starts: planner/state is published on demand, and a
    # subscriber declared after the node's start may reach its matching listener only after
    # the first scan under load (seen once: cmd_vel and status came, the state did not)
    inbox: queue.Queue = queue.Queue()
    subs = [session.declare_subscriber(keys.key(k), lambda s, k=k: inbox.put((k, s.payload.to_bytes())))
            for k in ("cmd_vel", "planner/state", "planner/status")]
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", algorithm,
                      "--namespace", keys.ns, "--connect", router, "--set", "v_max=0.2"])
    assert not wait_alive(session, keys, ["planner"], timeout_s=30)
    try:
        session.put(keys.goal, Goal(stamp_ns=5, x=2.0, y=0.0).to_bytes())
        k, data = _take(inbox, 1, "the goal")[0]
        assert k == "planner/status" and PlannerStatus.from_bytes(data).state == "ready"
        session.put(keys.scan, scan(100 * MS).to_bytes())
        session.put(keys.odom, odom(100 * MS).to_bytes())
        got = dict(_take(inbox, 3, "the first scan"))   # keys may interleave
        cmd = Twist.from_bytes(got["cmd_vel"])
        assert cmd.stamp_ns == 100 * MS and cmd.v == pytest.approx(0.2)
        state = PlannerState.from_bytes(got["planner/state"])
        assert state.algorithm == algorithm
        assert (len(state.predicted_path) == 34) == (algorithm == "papf")
        session.put(keys.scan, b"garbage")                            # dropped, node lives on
        session.put(keys.scan, scan(200 * MS).to_bytes())
        session.put(keys.odom, odom(200 * MS, x=1.95).to_bytes())
        got = dict(_take(inbox, 3, "the second scan"))
        assert PlannerStatus.from_bytes(got["planner/status"]).state == "reached"
    finally:
        for s in subs:
            s.undeclare()


def test_one_process_plans_for_each_robot_as_its_own_would(router, spawn, session):
    """``--robots pa,pb`` (a sim fleet's planners in one process): each robot's goal, scan
    and odometry on its own namespace get the command a planner of its own computes from
    them, bit for bit, on that namespace; each has its own token and its own parameters."""
    from nodes.planner.registry import make_planner

    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", "apf", "--robots",
                      "pa,pb", "--connect", router, "--set", "v_max=0.2"])
    robots = {"pa": (Keys("pa"), Goal(stamp_ns=5, x=2.0, y=0.0)),
              "pb": (Keys("pb"), Goal(stamp_ns=5, x=-1.0, y=1.5))}
    for keys, _ in robots.values():
        assert not wait_alive(session, keys, ["planner"], timeout_s=30)
    inbox: queue.Queue = queue.Queue()
    subs = [session.declare_subscriber(keys.key(k), lambda s, n=n, k=k: inbox.put(
        ((n, k), s.payload.to_bytes()))) for n, (keys, _) in robots.items()
        for k in ("cmd_vel", "planner/status")]
    try:
        for keys, goal in robots.values():
            session.put(keys.goal, goal.to_bytes())
        got = dict(_take(inbox, 2, "the goals"))
        assert {PlannerStatus.from_bytes(got[(n, "planner/status")]).state for n in robots} == {"ready"}
        for keys, _ in robots.values():
            session.put(keys.scan, scan(100 * MS).to_bytes())
            session.put(keys.odom, odom(100 * MS).to_bytes())
        got = dict(_take(inbox, 4, "the scans"))
        for name, (_, goal) in robots.items():
            own = make_planner("apf", None, ["v_max=0.2"])
            own.set_goal(goal)
            expected, _ = own.command(scan(100 * MS), odom(100 * MS), None)
            assert Twist.from_bytes(got[(name, "cmd_vel")]) == expected, name
        assert got[("pa", "cmd_vel")] != got[("pb", "cmd_vel")]
        p = _papf("param", "set", "planner", "v_max", "0.3", "--namespace", "pb", "--connect", router)
        assert p.returncode == 0, p.stderr
        values = {n: _papf("param", "get", "planner", "v_max", "--namespace", n, "--connect",
                           router).stdout.strip() for n in robots}
        assert values == {"pa": "apf.v_max = 0.2", "pb": "apf.v_max = 0.3"}
    finally:
        for s in subs:
            s.undeclare()


def test_a_keyed_fleet_planner_takes_each_robots_input_only_sealed_and_signed(router, spawn,
                                                                             session):
    """A run key (as papf run gives it): what a keyless peer puts on one robot's goal is
    refused and counted in that robot's health answer, not in the other's; a goal sealed and
    signed with the key gets that robot's signed ``ready``, and the other robot stays idle."""
    key = runauth.new_key()
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", "apf", "--robots",
                      "ka,kb", "--connect", router], env={runauth.ENV: key})
    ka, kb = Keys("ka"), Keys("kb")
    for keys in (ka, kb):
        assert not wait_alive(session, keys, ["planner"], timeout_s=30)
    inbox: queue.Queue = queue.Queue()
    subs = [session.declare_subscriber(keys.key("planner/status"), lambda s, k=keys.ns: inbox.put(
        (k, PlannerStatus.from_bytes(s.payload.to_bytes()), attachment_of(s)))) for keys in (ka, kb)]
    try:
        forged = Goal(stamp_ns=5, x=2.0, y=0.0)
        for _ in range(3):
            session.put(kb.goal, forged.to_bytes())                     # no seal: refused
        sealer = seal.Sealer(bytes.fromhex(key))
        goal = runauth.sign(Goal(stamp_ns=5, x=2.0, y=0.0), bytes.fromhex(key)).to_bytes()
        session.put(ka.goal, goal, attachment=sealer.seal(ka.goal, goal))
        ns, status, _att = _take(inbox, 1, "the sealed goal")[0]
        assert (ns, status.state) == ("ka", "ready") and runauth.verify(status, bytes.fromhex(key))

        def health(keys):
            replies = list(session.get(keys.key("health/planner"), timeout=10))
            return json.loads(replies[0].ok.payload.to_bytes())
        assert health(kb)["refused"] == {"goal": {"unsigned": 3}}, health(kb)
        assert health(ka)["refused"] == {}, health(ka)
        assert inbox.empty()                                            # kb never got a goal
    finally:
        for s in subs:
            s.undeclare()


def test_a_planner_refuses_robots_that_are_no_names():
    p = subprocess.run([sys.executable, "-m", "nodes.planner", "--robots", "pa,pa"],
                       capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert p.returncode == 2 and "each once" in p.stderr and "Traceback" not in p.stderr


def _papf(*args, env=None):
    return warm.run([sys.executable, "-m", "papf", *args], timeout=120, env=env)


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_a_keyed_planner_takes_changes_only_from_its_key(router, spawn, session, tmp_path,
                                                         monkeypatch):
    key = runauth.new_key()
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", "papf", "--connect",
                      router], env={runauth.ENV: key})
    assert not wait_alive(session, KEYS, ["planner"], 60.0)
    env = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}   # no key file: a stranger
    p = _papf("param", "set", "planner", "v_max", "0.3", "--connect", router, env=env)
    assert p.returncode == 2 and "not signed" in p.stderr, p.stderr
    p = _papf("param", "set", "planner", "d_o", "1e-9", "--connect", router, env=env)
    assert p.returncode == 2 and "[0.25, 25]" in p.stderr        # refused before sending
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    runauth.publish_key("rosbot", key)                             # as papf launch does
    p = _papf("param", "set", "planner", "v_max", "0.3", "--connect", router, env=env)
    assert p.returncode == 0 and p.stdout.strip() == "apf.v_max = 0.3", p.stderr
    p = _papf("param", "get", "planner", "apf.v_max", "--connect", router, "--json", env=env)
    assert '"apf.v_max": 0.3' in p.stdout

    for viewer_env, expect in (({}, 0.3), ({runauth.ENV: key}, 0.25)):
        port = free_port()
        spawn("viewer", [sys.executable, "-m", "nodes.viewer", "--connect", router, "--port",
                         str(port), "--world", "open"], env=viewer_env)
        client = FoxgloveClient(f"ws://127.0.0.1:{port}", timeout_s=30.0)
        try:
            assert client.wait_for(lambda c=client: "/log" in c.topics(), 30.0)
            client.request({"op": "setParameters",
                            "parameters": [{"name": "apf.v_max", "value": 0.25}]},
                           "parameterValues")
        finally:
            client.close()
        p = _papf("param", "get", "planner", "v_max", "--connect", router, env=env)
        assert p.stdout.strip() == f"apf.v_max = {expect}", (viewer_env, p.stdout, p.stderr)
