"""Seals (common/seal.py: run id, sequence, HMAC) and the nodes' intake policy (common/intake.py),
and parameter requests of another run — pure, no bus."""

from __future__ import annotations

from common import seal
from common.intake import AHEAD_OF_RUN_EXPECTED, BEFORE_RUN_EXPECTED, Trust
from schemas import Event

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
    assert driver.check("events", "rosbot/events", b"o", old.seal("rosbot/events", b"o"),
                        start) == "ok"                # the old run began first
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


def test_a_runs_node_tells_samples_from_before_any_run_apart_from_another_runs():
    """What the robot side sealed outside any run (NO_RUN: it had not joined yet, the samples
    still on a slow link as the run began) is refused as before_run, another run's as
    other_run; a follower keeps refusing an unrun command in a run as other_run."""
    meter = Trust(KEY, RUN)
    robot_before, robot_old = seal.Sealer(KEY, None), seal.Sealer(KEY, RUN2)
    assert meter.check("odom", "rosbot/odom", b"a", robot_before.seal("rosbot/odom", b"a")) \
        == seal.BEFORE_RUN
    assert meter.check("odom", "rosbot/odom", b"b", robot_old.seal("rosbot/odom", b"b")) \
        == seal.OTHER_RUN
    assert meter.counts() == {"odom": {seal.BEFORE_RUN: 1, seal.OTHER_RUN: 1}}
    assert meter.expected(seal.BEFORE_RUN) and not meter.expected(seal.OTHER_RUN)
    assert meter.alarming() == 1                      # the other run's sample only
    for k in range(BEFORE_RUN_EXPECTED):              # a robot side that never joins the run
        payload = f"late{k}".encode()
        meter.check("odom", "rosbot/odom", payload, robot_before.seal("rosbot/odom", payload))
    assert not meter.expected(seal.BEFORE_RUN) and meter.alarming() == 2
    driver = Trust(KEY, None)
    start = Event(stamp_ns=0, kind="run_started", source="launcher")
    assert driver.check("events", "rosbot/events", b"s",
                        seal.Sealer(KEY, RUN).seal("rosbot/events", b"s"), start) == "ok"
    teleop = seal.Sealer(KEY, None)
    assert driver.check("cmd_vel", "rosbot/cmd_vel", b"t", teleop.seal("rosbot/cmd_vel", b"t")) \
        == seal.OTHER_RUN


def test_a_follower_tells_a_new_runs_early_command_apart_from_an_old_runs():
    """A new run's first command may overtake its run_started on a jittered link: the robot
    side refuses it as ahead_of_run (expected, no warning) while it has not seen that run
    begin; a command of a run it saw begin and end (an old laptop's) stays other_run, and a
    run whose start never comes is warned of after AHEAD_OF_RUN_EXPECTED commands."""
    driver = Trust(KEY, None)
    laptop_old, laptop_new = seal.Sealer(KEY, RUN), seal.Sealer(KEY, RUN2)

    def command(sealer, payload):
        return driver.check("cmd_vel", "rosbot/cmd_vel", payload,
                            sealer.seal("rosbot/cmd_vel", payload))

    def event(sealer, kind, payload):
        return driver.check("events", "rosbot/events", payload,
                            sealer.seal("rosbot/events", payload),
                            Event(stamp_ns=0, kind=kind, source="launcher"))

    assert event(laptop_old, "run_started", b"s1") == seal.OK
    assert command(laptop_old, b"c1") == seal.OK
    assert event(laptop_old, "run_ended", b"e1") == seal.OK
    assert command(laptop_new, b"c2") == seal.AHEAD_OF_RUN       # ahead of its run_started
    assert driver.expected(seal.AHEAD_OF_RUN) and driver.alarming() == 0
    assert event(laptop_new, "run_started", b"s2") == seal.OK
    assert command(laptop_new, b"c3") == seal.OK
    assert command(laptop_old, b"c4") == seal.OTHER_RUN          # the old run's: a warning
    assert driver.alarming() == 1
    assert driver.counts() == {"cmd_vel": {seal.AHEAD_OF_RUN: 1, seal.OTHER_RUN: 1}}
    never = seal.Sealer(KEY, bytes(range(1, 9)))                 # its run_started never comes
    for k in range(AHEAD_OF_RUN_EXPECTED + 1):
        assert command(never, f"n{k}".encode()) == seal.AHEAD_OF_RUN
    assert not driver.expected(seal.AHEAD_OF_RUN) and driver.alarming() == 3
    assert Trust(KEY, RUN).check("cmd_vel", "rosbot/cmd_vel", b"p",
                                 laptop_new.seal("rosbot/cmd_vel", b"p")) == seal.OTHER_RUN


def test_a_parameter_request_of_another_run_is_refused():
    from common import runauth

    check = runauth.RequestCheck(KEY, RUN)
    assert check.ok(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY, RUN))
    assert not check.ok(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY, RUN2))
    assert not check.ok(runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY, None))
