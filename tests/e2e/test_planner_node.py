"""The planner node process answering goal and scan over a router."""

import queue
import sys

import pytest

from common.transport import wait_alive
from schemas import Keys
from schemas.messages import (
    Goal,
    PlannerState,
    PlannerStatus,
    Twist,
)
from tests.support.messages import odom, scan

MS = 1_000_000


@pytest.mark.parametrize("algorithm", ["apf", "papf"])
def test_node_answers_goal_and_scan_over_zenoh(router, spawn, session, algorithm):
    keys = Keys(f"plnode_{algorithm}")
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", algorithm,
                      "--namespace", keys.ns, "--connect", router, "--set", "v_max=0.2"])
    assert not wait_alive(session, keys, ["planner"], timeout_s=30)
    inbox: queue.Queue = queue.Queue()
    subs = [session.declare_subscriber(keys.key(k), lambda s, k=k: inbox.put((k, s.payload.to_bytes())))
            for k in ("cmd_vel", "planner/state", "planner/status")]
    try:
        session.put(keys.goal, Goal(stamp_ns=5, x=2.0, y=0.0).to_bytes())
        k, data = inbox.get(timeout=30)
        assert k == "planner/status" and PlannerStatus.from_bytes(data).state == "ready"
        session.put(keys.scan, scan(100 * MS).to_bytes())
        session.put(keys.odom, odom(100 * MS).to_bytes())
        got = dict(inbox.get(timeout=30) for _ in range(3))   # keys may interleave
        cmd = Twist.from_bytes(got["cmd_vel"])
        assert cmd.stamp_ns == 100 * MS and cmd.v == pytest.approx(0.2)
        state = PlannerState.from_bytes(got["planner/state"])
        assert state.algorithm == algorithm
        assert (len(state.predicted_path) == 34) == (algorithm == "papf")
        session.put(keys.scan, b"garbage")                            # dropped, node lives on
        session.put(keys.scan, scan(200 * MS).to_bytes())
        session.put(keys.odom, odom(200 * MS, x=1.95).to_bytes())
        got = dict(inbox.get(timeout=30) for _ in range(3))
        assert PlannerStatus.from_bytes(got["planner/status"]).state == "reached"
    finally:
        for s in subs:
            s.undeclare()
