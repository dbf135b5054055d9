"""Issue 20, items 1, 2 and 10: no setting switches avoidance off, every live change is
signed with the run's key, observers may not query, goals nowhere are refused at once.
Property-based over the whole safety ranges and over tampered requests."""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common import runauth
from common.errors import ConfigError
from nodes.planner import settings as S
from nodes.planner.params import answer, current
from nodes.planner.registry import PLANNERS, load_params, make_planner
from papf.cli import main
from papf.robot.certs import access_control

FLOORS = {"d_o": S.D_O_MIN_M, "k_vo_l": S.K_VO_L_MIN, "q_o": -S.CHARGE_MIN, "q_v": -S.CHARGE_MIN}
PROBES = ["d_o=1e-9", "k_vo_l=1e-300", "q_o=-1e-300", "q_v=-1e-300", "d_o=0.2",
          "arapf.k_ro_l=1e-9", "wang.k_rep_l=1e-9", "wang.rho_0=1e-9"]


@pytest.mark.parametrize("setting", PROBES)
def test_the_issues_probes_are_refused(setting):
    name = setting.split("=")[0]
    planner = name.split(".")[0] if "." in name else "papf"
    with pytest.raises(ConfigError, match="must be"):
        load_params(planner, None, [setting])


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(sorted(FLOORS)), frac=st.floats(0.0, 1.0, exclude_max=True))
def test_no_value_between_zero_and_the_floor_is_taken(name, frac):
    value = FLOORS[name] * frac
    with pytest.raises(ConfigError):
        load_params("papf", None, [f"{name}={value!r}"])


@settings(max_examples=80, deadline=None)
@given(k=st.floats(S.K_VO_L_MIN, 50.0), qv=st.floats(-5.0, -S.CHARGE_MIN),
       qo=st.floats(-5.0, -S.CHARGE_MIN))
def test_the_repulsion_product_has_its_own_floor(k, qv, qo):
    sets = [f"k_vo_l={k!r}", f"q_v={qv!r}", f"q_o={qo!r}"]
    pull = 5.0 * 1.0 / (k * abs(qo))   # the default k_vg q_g over k_vo_l |q_o| (q_v in both)
    if k * qv * qo >= S.REPULSION_MIN and pull <= S.ATTRACTION_RATIO_MAX:
        apf, _ = load_params("apf", None, sets)
        assert apf.k_vo_l * apf.q_v * apf.q_o >= S.REPULSION_MIN
    elif k * qv * qo < S.REPULSION_MIN:
        with pytest.raises(ConfigError, match=r"k_vo_l\*q_v\*q_o"):
            load_params("apf", None, sets)
    else:   # pushed hard enough, but pulled harder still (the attraction ratio's ceiling)
        with pytest.raises(ConfigError, match=r"k_vg\*q_g/\(k_vo_l\*\|q_o\|\)"):
            load_params("apf", None, sets)


def test_every_swept_safety_range_starts_at_its_measured_floor():
    from nodes.planner.arapf import settings as AR
    from nodes.planner.wang import settings as W

    measured = {"d_o": S.D_O_MIN_M, "k_vo_l": S.K_VO_L_MIN, "k_ro_l": AR.K_RO_L_MIN,
                "k_rep_l": W.K_REP_L_MIN, "rho_0": W.RHO_0_MIN_M}
    for table in (S.APF, AR.ARAPF, W.WANG):
        for name, floor in measured.items():
            if name in table:
                assert table[name].safety and table[name].lo == floor and not table[name].lo_open
    for name in ("q_v", "q_o"):
        assert S.APF[name].hi == -S.CHARGE_MIN and not S.APF[name].hi_open
    apf, algo = load_params("arapf")
    S.check_strength(apf)
    PLANNERS["arapf"].check_strength(apf, algo)   # AR-APF's own product, at the defaults


KEY = bytes.fromhex(runauth.new_key())


def _ask(planner, request: dict, check) -> dict:
    return answer("papf", planner, json.dumps(request).encode(), check)[0]


def test_a_keyed_planner_lists_to_anyone_but_changes_only_for_its_key():
    planner = make_planner("papf")
    check = runauth.RequestCheck(KEY)
    before = current("papf", planner)
    assert _ask(planner, {}, check)["params"] == before            # reading is open
    reply = _ask(planner, {"set": ["apf.d_o=0.6"]}, check)          # unsigned
    assert "not signed" in reply["error"] and current("papf", planner) == before
    other = runauth.sign_request({"set": ["apf.d_o=0.6"]}, bytes(16))
    assert "not signed" in _ask(planner, other, check)["error"]
    signed = runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY)
    assert _ask(planner, signed, check)["error"] == ""
    assert current("papf", planner)["apf.d_o"] == 0.6
    assert "not signed" in _ask(planner, signed, check)["error"]    # a replay: nonce seen
    low = runauth.sign_request({"set": ["apf.d_o=1e-9"]}, KEY)      # signed, still checked
    assert "must be" in _ask(planner, low, check)["error"]
    assert current("papf", planner)["apf.d_o"] == 0.6


@settings(max_examples=60, deadline=None)
@given(sets=st.lists(st.text(max_size=30), min_size=1, max_size=3),
       tamper=st.sampled_from(["set", "nonce", "auth", "extra"]))
def test_any_tampered_request_is_refused(sets, tamper):
    check = runauth.RequestCheck(KEY)
    req = runauth.sign_request({"set": sets}, KEY)
    bad = dict(req)
    if tamper == "set":
        bad["set"] = sets + ["apf.d_o=1e-9"]
    elif tamper == "nonce":
        bad["nonce"] = req["nonce"][::-1] + "0"
    elif tamper == "auth":
        bad["auth"] = ("0" if req["auth"][0] != "0" else "1") + req["auth"][1:]
    else:
        bad["x"] = 1
    assert not check.ok(bad)
    assert check.ok(req) and not check.ok(req)


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=300))
def test_garbage_queries_change_nothing(payload):
    planner = make_planner("apf")
    before = current("apf", planner)
    reply, changed = answer("apf", planner, payload, runauth.RequestCheck(KEY))
    assert changed == [] and current("apf", planner) == before and "params" in reply


def test_the_observer_may_not_query():
    acl = access_control()
    policies = {p["id"]: p["rules"] for p in acl["policies"]}
    rules = {r["id"]: r for r in acl["rules"]}
    assert "query" not in policies["observer"] and "query" in policies["planner"]
    assert all("query" not in rules[r]["messages"] for r in policies["observer"])


@pytest.mark.parametrize("argv", [["goal", "nan", "0"], ["goal", "1e308", "0"],
                                  ["goal", "0", "inf"], ["goal", "1", "1", "--tolerance", "-1"],
                                  ["param", "set", "planner", "d_o"], ["param", "list", "viewr"]])
def test_goals_and_param_calls_that_go_nowhere_are_refused_at_once(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        rc = main(argv)
        raise SystemExit(rc)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err


def test_a_second_launch_in_a_namespace_is_refused(tmp_path, monkeypatch):
    import subprocess
    import sys

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        path = runauth.key_file("lab/r1")
        path.parent.mkdir(mode=0o700)
        path.write_text(f"{'ab' * 16} {other.pid}\n")
        with pytest.raises(runauth.NamespaceTaken, match="in use by another launch"):
            runauth.publish_key("lab/r1", runauth.new_key())
    finally:
        other.kill()
        other.wait()
    key = runauth.new_key()          # its launcher died: the namespace is free again
    runauth.publish_key("lab/r1", key)
    assert runauth.read_key("lab/r1") == bytes.fromhex(key)
