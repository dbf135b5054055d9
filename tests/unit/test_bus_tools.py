"""papf topic / goal / teleop without a bus: decoding, key names, rates, progress, teleop keys."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common import ros2
from common.errors import ConfigError
from papf.bus import topics
from papf.bus.decode import CDR, MSGPACK, RAW, as_text, decode, ros_type_for_key, safe_text
from papf.bus.stats import HzStats, stamp_rate
from papf.bus.teleop import TeleopState, parse_keys
from papf.bus.topics import Inbox, _echo
from papf.cli import main
from papf.console.progress import DecileProgress
from schemas import Keys, Scan
from tests.support.cli import papf

KEYS = Keys("rosbot")


SETTINGS = settings(max_examples=60, deadline=None)


def _scan(stamp: int = 100) -> Scan:
    return Scan(stamp_ns=stamp, angle_min=-math.pi, angle_increment=0.1, range_min=0.2,
                range_max=25.0, ranges=[1.0] * 20)


# -- decoding ---------------------------------------------------------------------------------
def test_decode_our_msgpack_by_its_type():
    d = decode("rosbot/scan", _scan(7).to_bytes())
    assert (d.encoding, d.type_name, d.stamp_ns, d.error) == (MSGPACK, "papf/Scan/v1", 7, "")
    text = as_text(d.value)
    assert "ranges: [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, … (20 items" in text
    assert "1.0, " * 19 in as_text(d.value, max_items=None)


def test_decode_bridge_cdr_by_key_and_by_override():
    data = ros2.encode(ros2.odometry(2_500_000_000, 1.5, -2.0, 0.3, 0.2, 0.1), ros2.ODOMETRY)
    d = decode("odometry/filtered", data)
    assert (d.encoding, d.type_name, d.stamp_ns) == (CDR, ros2.ODOMETRY, 2_500_000_000)
    assert d.value["pose"]["pose"]["position"]["x"] == 1.5
    assert ros_type_for_key("robot1/odometry/filtered") == ros2.ODOMETRY   # bridge namespace
    unknown = decode("my/topic", data)
    assert unknown.type_name == "" and "--ros-type" in unknown.value
    forced = decode("my/topic", data, ros_type=ros2.ODOMETRY)
    assert forced.value["twist"]["twist"]["linear"]["x"] == pytest.approx(0.2)
    wrong = decode("cmd_vel", data, ros_type="no_pkg/msg/Nothing")
    assert "not a ROS 2 Humble type" in wrong.error


def test_decode_invalid_and_raw_payloads_are_shown_not_raised():
    import msgpack

    bad = msgpack.packb({"_type": "papf/Twist/v1", "stamp_ns": 1, "v": "fast", "w": 0.0})
    d = decode("rosbot/cmd_vel", bad)
    assert d.type_name == "papf/Twist/v1" and "expected a number" in d.error
    assert decode("x", b"\x01\x02\x03").encoding == RAW


def test_resolve_key_namespace_and_bridge_names():
    assert topics.resolve_key("scan", KEYS) == "rosbot/scan"
    assert topics.resolve_key("planner/state", Keys("lab/r1")) == "lab/r1/planner/state"
    assert topics.resolve_key("/scan", KEYS) == "scan"
    assert topics.resolve_key("rosbot/**", KEYS) == "rosbot/**"
    assert topics.resolve_key("/odometry/filtered", KEYS, "rmw_zenoh", 3) == "3/odometry/filtered/*/*"
    assert topics.resolve_key("scan", KEYS, "rmw_zenoh", 3) == "rosbot/scan"


def test_decode_rmw_zenoh_cdr_by_the_type_its_key_names():
    # rmw_zenoh's key as ros2/rmw_zenoh liveliness_utils.cpp TopicInfo::TopicInfo writes it
    key = ("0/robot1/odom/nav_msgs::msg::dds_::Odometry_/"
           "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0")
    data = ros2.encode(ros2.odometry(7, 1.0, 2.0, 0.0, 0.0, 0.0), ros2.ODOMETRY)
    d = decode(key, data)
    assert (d.encoding, d.type_name, d.stamp_ns) == (CDR, ros2.ODOMETRY, 7)
    assert ros_type_for_key("0/scan/not_a_type/RIHS01_00") is None


# -- rates, progress --------------------------------------------------------------------------
def test_hz_stats_by_arrival_and_by_stamp():
    st = HzStats(window=100)
    for i in range(21):                       # 20 Hz arrivals, 10 Hz in stamps (lockstep 2x)
        st.add(i * 0.05, i * 100_000_000)
    r = st.rate()
    assert r.hz == pytest.approx(20.0) and r.stamp_hz == pytest.approx(10.0)
    assert r.window == 21 and r.sd_s == pytest.approx(0.0, abs=1e-9)
    assert "20.000 Hz" in r.line("rosbot/scan")
    assert math.isnan(HzStats().rate().hz)
    assert stamp_rate([5, 6, 7, 0, 100_000_000, 200_000_000]) == pytest.approx(10.0)  # new run


def test_decile_progress_piped_prints_one_line_per_ten_percent():
    lines: list[str] = []
    with DecileProgress("replay", enabled=None, out=lines.append) as p:
        for i in range(1001):
            p.fraction(i / 1000)
    assert len(lines) == 11 and lines[0].startswith("replay:   0 %") and "100 %" in lines[-1]
    dist: list[str] = []
    with DecileProgress("goal", out=dist.append) as p:
        for d in (10.0, 9.0, 9.5, 4.9, 0.0):   # going back does not print again
            p.distance(d)
    assert [x.split(":")[1].strip() for x in dist] == ["0 %", "10 %", "51 %", "100 %"]


# -- teleop (pure, then through a pseudo-terminal) --------------------------------------------
def test_teleop_keys_and_limits():
    assert parse_keys("wW\x1b[A\x1b[Dq") == ["w", "w", "up", "left", "q"]
    st = TeleopState(max_v=0.1, max_w=0.4)
    for k in ("w", "up", "w", "left", "left", "left"):
        st.press(k)
    assert (st.v, st.w) == (0.1, 0.4)          # clamped at the teleop's own limits
    st.press("right")
    assert st.w == pytest.approx(0.2)
    st.press(" ")
    assert (st.v, st.w) == (0.0, 0.0)
    assert not st.press("z") and not st.quit
    st.press("down")
    assert st.v == -0.05
    st.press("q")
    assert st.quit and (st.v, st.w) == (0.0, 0.0)
    with pytest.raises(ConfigError, match="0.9"):
        TeleopState(max_v=2.0)


@SETTINGS
@given(st.lists(st.integers(0, 3000), min_size=1, max_size=300))
def test_inbox_stays_within_its_bounds_and_keeps_the_newest(sizes):
    inbox = Inbox(None, "x", max_items=50, max_bytes=20_000)
    for i, n in enumerate(sizes):
        inbox.put(f"k{i}", b"x" * n, float(i))
        assert len(inbox) <= 50
        assert len(inbox) == 1 or sum(len(d) for _, d, _ in inbox._items) <= 20_000
    assert inbox.dropped + len(inbox) == len(sizes)
    assert inbox._items[-1][0] == f"k{len(sizes) - 1}"   # the newest is never the one dropped


def test_echo_under_a_flood_says_it_dropped_and_how_many():
    inbox = Inbox(None, "x", max_items=10)
    for i in range(1000):
        inbox.put("rosbot/odom", b"\x80", float(i))
    printed, notes = [], []
    shown = _echo(inbox, printed.append, 0, 0.0, None, 8, False, lambda: len(printed) >= 10,
                  notes.append)
    assert shown == 10 and inbox.dropped == 990
    assert len(notes) == 1 and "dropped" in notes[0]


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.text(max_size=400))
def test_echoed_text_has_no_control_characters_and_is_bounded(text):
    shown = safe_text(text)
    assert shown.isprintable() and len(shown) <= 200 * 10 + 40
    line = as_text({"k\x1b": text})
    assert "\x1b" not in line and "\x07" not in line


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


def test_a_broken_topic_pub_value_names_its_column():
    res = papf("topic", "pub", "cmd_vel", "{v: 0.1, w: 0.0", "--once")
    assert res.returncode == 2
    assert res.stderr.startswith("papf topic pub: VALUE '{v: 0.1, w: 0.0' is not YAML/JSON: "
                                 "column 16: expected ',' or '}'")
