"""The planner's parameter service (nodes/planner/params.py) over a real router: an
unauthenticated peer changes nothing, the run key's holder changes settings within their ranges."""

from __future__ import annotations

import json
import threading

import pytest
import zenoh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common import runauth
from common.transport import zenoh_config
from nodes.planner.params import answer, current
from nodes.planner.registry import make_planner

KEY = bytes.fromhex(runauth.new_key())


@pytest.fixture
def keyed_planner(router):
    """The planner node's parameter queryable (nodes.planner.params.answer, keyed) on the bus."""
    planner, check, lock = make_planner("papf"), runauth.RequestCheck(KEY), threading.Lock()

    def on_query(q):
        payload = q.payload.to_bytes() if q.payload is not None else b""
        with lock:
            reply, _ = answer("papf", planner, payload, check)
        q.reply(q.key_expr, json.dumps(reply).encode())

    with zenoh.open(zenoh_config("client", [router])) as s:
        qa = s.declare_queryable("rosbot/planner/params", on_query)
        yield planner, s
        qa.undeclare()


def _get(session, payload: bytes) -> dict | None:
    for r in session.get("rosbot/planner/params", payload=payload, timeout=3.0):
        if r.ok is not None:
            return json.loads(r.ok.payload.to_bytes())
    return None


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(payload=st.one_of(
    st.binary(max_size=200),
    st.builds(lambda s: json.dumps({"set": s}).encode(),
              st.lists(st.sampled_from(["apf.d_o=1e-9", "apf.v_max=0.9", "apf.k_vo_l=1e-300",
                                        "papf.q_q=-1e-9", "apf.d_o=0.6"]), min_size=1, max_size=3)),
    st.builds(lambda s, a, n: json.dumps({"set": s, "auth": a, "nonce": n}).encode(),
              st.lists(st.text(max_size=20), max_size=2), st.text(max_size=40),
              st.text(max_size=20))))
def test_an_unauthenticated_peer_changes_nothing(keyed_planner, payload):
    planner, session = keyed_planner
    before = current("papf", planner)
    reply = _get(session, payload)
    assert reply is not None and reply["params"] == before and current("papf", planner) == before


def test_the_run_key_holder_changes_within_the_ranges(keyed_planner):
    planner, session = keyed_planner
    ok = _get(session, json.dumps(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY)).encode())
    assert ok["error"] == "" and current("papf", planner)["apf.d_o"] == 0.6
    low = _get(session, json.dumps(runauth.sign_request({"set": ["apf.d_o=1e-9"]}, KEY)).encode())
    assert "must be" in low["error"] and current("papf", planner)["apf.d_o"] == 0.6
