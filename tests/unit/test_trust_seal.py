"""Issue 31: seals (run id, sequence, HMAC), the nodes' intake policy, stamp windows, the
recorder's budgets and the laptop's resume decision — pure, no bus."""

from __future__ import annotations

import pytest

from common import seal
from common.errors import ConfigError
from common.intake import Trust
from common.units import MAX_STAMP_NS, StampGuard
from nodes.recorder.budget import QUEUE_FULL, Budget
from papf.launch.resume import Journal, RobotRun, decide, write_journal
from schemas import Event
from tests.support.messages import odom as _odom

KEY, OTHER = b"k" * 16, b"o" * 16
RUN, RUN2 = bytes.fromhex("11" * 8), bytes.fromhex("22" * 8)


def _sealed(key=KEY, run=RUN, key_expr="rosbot/goal", payload=b"goal", sealer=None):
    sealer = sealer or seal.Sealer(key, run)
    return payload, sealer.seal(key_expr, payload), sealer


def test_a_seal_verifies_once_and_a_replay_is_refused():
    opener = seal.Opener(KEY, RUN)
    payload, att, _ = _sealed()
    assert opener.check("rosbot/goal", payload, att)[0] == seal.OK
    assert opener.check("rosbot/goal", payload, att)[0] == seal.REPLAY    # the same bytes again


def test_no_key_another_key_another_key_expr_or_run_is_refused():
    opener = seal.Opener(KEY, RUN)
    payload, att, _ = _sealed()
    assert opener.check("rosbot/goal", payload, None)[0] == seal.UNSIGNED
    assert opener.check("rosbot/goal", b"goaX", att)[0] == seal.FORGED         # payload changed
    assert opener.check("rosbot/cmd_vel", payload, att)[0] == seal.FORGED      # moved to a key
    assert opener.check("rosbot/goal", *_sealed(key=OTHER)[:2])[0] == seal.FORGED
    assert opener.check("rosbot/goal", *_sealed(run=RUN2)[:2])[0] == seal.OTHER_RUN


def test_a_restarted_sender_goes_on_above_its_predecessor():
    """seq is the sender's wall clock: a new process needs no state to stay in order."""
    opener = seal.Opener(KEY, RUN)
    clock = iter(range(1000, 2000)).__next__
    first = seal.Sealer(KEY, RUN, clock=clock)
    assert opener.check("k", b"a", first.seal("k", b"a"))[0] == seal.OK
    again = seal.Sealer(KEY, RUN, clock=clock)
    assert opener.check("k", b"b", again.seal("k", b"b"))[0] == seal.OK


def test_a_follower_obeys_commands_of_the_run_it_is_in_only():
    driver = Trust(KEY, None)                       # the robot side: a key, no run given
    launcher, planner, old = (seal.Sealer(KEY, RUN), seal.Sealer(KEY, RUN),
                              seal.Sealer(KEY, RUN2))
    start = Event(stamp_ns=0, kind="run_started", source="launcher")
    assert driver.check("events", "rosbot/events", b"s", launcher.seal("rosbot/events", b"s"),
                        start) == "ok"
    assert driver.run_hex() == RUN.hex()
    assert driver.check("cmd_vel", "rosbot/cmd_vel", b"t",
                        planner.seal("rosbot/cmd_vel", b"t")) == "ok"
    assert driver.check("cmd_vel", "rosbot/cmd_vel", b"u",
                        old.seal("rosbot/cmd_vel", b"u")) == seal.OTHER_RUN
    assert driver.check("cmd_vel", "rosbot/cmd_vel", b"v", None) == seal.UNSIGNED
    assert driver.counts()["cmd_vel"] == {seal.OTHER_RUN: 1, seal.UNSIGNED: 1}


def test_a_stale_run_started_does_not_start_a_run():
    driver = Trust(KEY, None)
    stale = seal.Sealer(KEY, RUN, clock=lambda: 1)  # sealed in 1970: captured long ago
    start = Event(stamp_ns=0, kind="run_started", source="launcher")
    assert driver.check("events", "rosbot/events", b"s", stale.seal("rosbot/events", b"s"),
                        start) == "stale"
    assert driver.run_hex() == ""


def test_a_fixed_run_node_takes_its_run_only_and_no_key_takes_all():
    planner = Trust(KEY, RUN)
    assert planner.check("scan", "rosbot/scan", *_sealed(key_expr="rosbot/scan", run=RUN2)[:2]) \
        == seal.OTHER_RUN
    assert Trust(None, None).check("scan", "rosbot/scan", b"x", None) == "ok"


def test_a_stamp_from_the_future_is_dropped_and_moves_nothing():
    wall = [0]
    guard = StampGuard({"scan"}, wall=lambda: wall[0])
    assert guard.check("scan", _odom(100_000_000)) == ""
    assert "future" in guard.check("scan", _odom(MAX_STAMP_NS))
    wall[0] = 10_000_000   # 10 ms later: the real stream goes on
    assert guard.check("scan", _odom(200_000_000)) == ""


def test_samples_a_little_ahead_are_outvoted_by_the_real_stream():
    guard = StampGuard({"scan"}, wall=lambda: 0)
    assert guard.check("scan", _odom(1_000_000_000)) == ""
    assert guard.check("scan", _odom(1_550_000_000)) == ""          # spoofed, 0.55 s ahead
    real = [guard.check("scan", _odom(1_100_000_000 + i * 100_000_000)) for i in range(6)]
    assert all("older" in why for why in real[:4])                   # dropped a while...
    assert real[4:] == ["", ""] and guard.resyncs == 1                # ...then the stream wins


def test_a_flood_on_one_key_cannot_starve_another():
    budget = Budget(queued_max=1_000_000, clock=lambda: 0.0)
    flood = [budget.admit("rosbot/scan", 100_000) for _ in range(20)]
    assert QUEUE_FULL in flood
    assert all(budget.admit("rosbot/odom", 100) == "" for _ in range(50))
    assert budget.counts()["rosbot/scan"][QUEUE_FULL] == flood.count(QUEUE_FULL)


def test_a_laptop_that_comes_back_must_say_what_it_wants(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    (tmp_path / f"papf-{__import__('os').getuid()}").mkdir(mode=0o700)
    robot = RobotRun(RUN.hex(), True, 12_000_000_000, 1.0, 0.0)
    with pytest.raises(ConfigError, match="--resume.*--new-run"):
        decide(robot, "refuse", "rosbot", RUN2.hex())
    assert decide(robot, "new", "rosbot", RUN2.hex()) == (RUN2.hex(), None)
    with pytest.raises(ConfigError, match="no journal"):
        decide(robot, "resume", "rosbot", RUN2.hex())
    write_journal("rosbot", Journal(RUN.hex(), "w", (3.0, 0.0, 0.1), charge_mAh=1.5))
    run, journal = decide(robot, "resume", "rosbot", RUN2.hex())
    assert run == RUN.hex() and journal.charge_mAh == 1.5
    assert decide(None, "refuse", "rosbot", RUN2.hex()) == (RUN2.hex(), None)
    with pytest.raises(ConfigError, match="no run"):
        decide(None, "resume", "rosbot", RUN2.hex())


def test_a_parameter_request_of_another_run_is_refused():
    from common import runauth

    check = runauth.RequestCheck(KEY, RUN)
    assert check.ok(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY, RUN))
    assert not check.ok(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY, RUN2))
    assert not check.ok(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY, None))
