"""The link emulator's pure core (papf.link.schedule) and its specs (papf.link.spec): no sockets."""

from __future__ import annotations

import pytest

from common.errors import ConfigError
from papf.link.schedule import (
    RTO_MIN_S,
    Direction,
    Outage,
    OutageSchedule,
    merge,
    quantile,
    resume_after,
)
from papf.link.spec import PROFILES, LinkSpec, parse_spec, uniform, with_overrides
from papf.link.stats import DirectionStats, percentile
from tests.support.cli import papf


def _direction(text: str, direction: str = "out") -> Direction:
    spec = parse_spec(text)
    return Direction(spec, direction, OutageSchedule(spec))


def _deliveries(d: Direction, arrivals, size: int = 100) -> list:
    return [d.depart(t, size) for t in arrivals]


# -- delay, jitter, order ----------------------------------------------------------------------
def test_a_fixed_delay_is_added_to_every_chunk():
    d = _direction("delay=100")
    assert _deliveries(d, [0.0, 0.5, 1.0]) == pytest.approx([0.1, 0.6, 1.1])


def test_jitter_stays_in_its_range_and_delivery_never_goes_backwards():
    d = _direction("delay=200,jitter=150,jitter_period=0")
    arrivals = [i * 0.01 for i in range(2000)]
    out = _deliveries(d, arrivals)
    assert out == sorted(out)                                   # one TCP stream: in order
    extra = [o - a for o, a in zip(out, arrivals, strict=True)]
    assert min(extra) >= 0.2 - 1e-9 and max(extra) <= 0.35 + 1e-9


def test_held_jitter_keeps_the_published_spread():
    """Jitter drawn once per period: the applied delays spread over 200-350 ms (a new value
    per chunk would hold most chunks behind the slowest one, near 350 ms)."""
    d = _direction("delay=200,jitter=150,jitter_period=100")
    arrivals = [i * 0.01 for i in range(20_000)]
    extra = sorted(o - a for o, a in zip(_deliveries(d, arrivals), arrivals, strict=True))
    assert percentile(extra, 10) < 0.24 and percentile(extra, 50) == pytest.approx(0.275, abs=0.03)
    assert percentile(extra, 90) > 0.31


def test_the_schedule_is_a_function_of_the_seed_and_the_arrivals():
    arrivals = [i * 0.013 for i in range(500)]
    a = _deliveries(_direction("wifi-bad,seed=3"), arrivals)
    assert a == _deliveries(_direction("wifi-bad,seed=3"), arrivals)
    assert a != _deliveries(_direction("wifi-bad,seed=4"), arrivals)
    assert a != _deliveries(_direction("wifi-bad,seed=3", "back"), arrivals)


def test_quantiles_are_interpolated():
    pts = ((0.0, 0.0), (0.5, 1.0), (0.9, 9.5), (1.0, 149.5))
    assert quantile(pts, 0.0) == 0.0 and quantile(pts, 0.25) == 0.5
    assert quantile(pts, 0.9) == 9.5 and quantile(pts, 1.0) == 149.5


# -- rate --------------------------------------------------------------------------------------
def test_the_rate_limit_serializes_chunks():
    d = _direction("rate=8")                   # 8 kbit/s = 1000 bytes per second
    out = _deliveries(d, [0.0, 0.0, 0.0], size=500)
    assert out == pytest.approx([0.5, 1.0, 1.5])


def test_rate_back_applies_to_the_back_direction_only():
    spec = parse_spec("rate=8,rate_back=16")
    assert spec.rate("out") == 8 and spec.rate("back") == 16
    back = Direction(spec, "back", OutageSchedule(spec))
    assert back.depart(0.0, 1000) == pytest.approx(0.5)


# -- loss --------------------------------------------------------------------------------------
def test_a_lost_chunk_waits_a_retransmission_timeout_and_holds_those_behind_it():
    d = _direction("delay=10,loss=20,jitter_period=0")
    arrivals = [i * 0.01 for i in range(1000)]
    out = _deliveries(d, arrivals)
    assert 100 < d.lost < 300
    assert max(o - a for o, a in zip(out, arrivals, strict=True)) == pytest.approx(0.01 + RTO_MIN_S)
    assert out == sorted(out)


# -- outages -----------------------------------------------------------------------------------
def test_nothing_is_delivered_during_a_stall_outage_and_tcp_resumes_at_its_next_retry():
    d = _direction("delay=50,outage=10@20")
    arrivals = [i * 0.1 for i in range(400)]
    out = _deliveries(d, arrivals)
    assert not [o for o in out if 20.0 <= o < 30.0]
    resume = resume_after(Outage(20.0, 30.0), d.rto_s)
    assert resume == pytest.approx(20.0 + 0.2 * (2 ** 6 - 1))   # 0.2, 0.4, ... 6.4 s waits
    held = [o for o, a in zip(out, arrivals, strict=True) if 19.95 <= a < resume]
    assert held and min(held) == pytest.approx(resume + 0.05)


def test_the_retransmission_timeout_is_what_tcp_settles_on_over_the_link():
    from papf.link.schedule import rto_estimate

    assert rto_estimate(PROFILES["lan"]) == RTO_MIN_S == rto_estimate(PROFILES["wifi"])
    # 200 + U(0, 150) ms one way: srtt 550 ms, rttvar ~53 ms -> ~0.76 s
    assert rto_estimate(parse_spec("delay=200,jitter=150")) == pytest.approx(0.762, abs=0.01)
    assert rto_estimate(parse_spec("delay=500")) == pytest.approx(1.0)


def test_the_retry_backoff_is_capped():
    assert resume_after(Outage(0.0, 1000.0), 0.2) < 1000.0 + 120.0 + 1e-9


def test_a_reset_outage_drops_what_enters_or_flies_during_it():
    d = _direction("delay=50,outage=10@20,outage_mode=reset")
    assert d.depart(19.96, 100) is None       # in flight when the link went
    assert d.depart(25.0, 100) is None
    assert d.depart(30.0, 100) == pytest.approx(30.05)
    assert d.dropped == 2


def test_outages_merge_and_random_ones_are_seeded():
    assert merge([Outage(5, 8), Outage(0, 2), Outage(1, 3)]) == [Outage(0, 3), Outage(5, 8)]
    spec = parse_spec("outage_rate=2,outage_mean=1,seed=7")
    a, b = OutageSchedule(spec), OutageSchedule(spec)
    got = a.until(1800.0)
    assert got == b.until(1800.0) and 30 < len(got) < 100       # ~2 per minute for 30 min
    assert all(o.random for o in got)
    assert OutageSchedule(parse_spec("outage_rate=2,seed=8")).until(1800.0) != got


def test_an_outage_schedule_without_origin_has_no_outage():
    spec = parse_spec("outage=10@0")
    sched = OutageSchedule(spec, origin=float("inf"))
    assert sched.at(5.0) is None and sched.between(0.0, 100.0) is None
    sched.origin = 100.0
    assert sched.at(105.0) == Outage(0.0, 10.0)


# -- specs and profiles ------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(PROFILES))
def test_every_profile_round_trips_through_its_text(name):
    spec = PROFILES[name]
    assert parse_spec(spec.to_text()) == spec
    assert name in spec.describe()


def test_explicit_numbers_override_a_profile():
    spec = parse_spec("wifi,delay=20,outage=10@20")
    assert spec.delay_ms == 20 and spec.jitter == PROFILES["wifi"].jitter
    assert spec.outages == ((10.0, 20.0),)
    assert with_overrides(spec, jitter=uniform(5)).jitter_max_ms == 5


@pytest.mark.parametrize("text, says", [
    ("wfi", "did you mean 'wifi'"), ("delay=nan", "delay=nan"), ("delay=-1", "[0, 60000]"),
    ("outage=10", "LENGTH@START"), ("outage=0@5", "outage length"), ("rate=0", "rate"),
    ("loss=80", "loss"), ("dealy=3", "did you mean 'delay'"), ("wifi,lte", "key=value"),
    ("", "empty"), ("jitter=0.5:1/1:2", "rise from P=0"), ("outage_mode=drop", "stall"),
])
def test_bad_specs_say_what_is_valid(text, says):
    with pytest.raises(ConfigError, match=None) as err:
        parse_spec(text)
    assert says in str(err.value)


def test_the_default_spec_is_a_perfect_link():
    d = Direction(LinkSpec(), "out", OutageSchedule(LinkSpec()))
    assert d.depart(1.0, 10_000) == 1.0


def test_delay_stats_keep_a_bounded_reservoir():
    s = DirectionStats()
    for i in range(120_000):
        s.add(10, i / 120_000)
    j = s.to_json()
    assert s.chunks == 120_000 and len(s.delays) == 50_000
    assert j["delay_ms"]["p50"] == pytest.approx(500, abs=20)


# -- the command line: one line and exit 2 before anything listens --------------------------------
@pytest.mark.parametrize("args, says", [
    (["--profile", "wfi"], "did you mean 'wifi'"),
    (["--delay", "nan"], "--delay=nan"),
    (["--outage", "10"], "LENGTH@START"),
    (["--spec", "delay=1,foo=2"], "unknown link spec key 'foo'"),
])
def test_papf_link_refuses_bad_flags_with_one_line(args, says):
    out = papf("link", "--listen", "tcp/127.0.0.1:1", "--to", "tcp/127.0.0.1:2", *args, timeout=60)
    assert out.returncode == 2 and says in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr


def test_papf_link_refuses_a_bad_endpoint_and_an_existing_stats_file(tmp_path):
    stats = tmp_path / "s.json"
    stats.write_text("mine")
    for args, says in ((["--listen", "7448", "--to", "tcp/127.0.0.1:2"], "tcp/HOST:PORT"),
                       (["--listen", "tcp/127.0.0.1:0", "--to", "tcp/127.0.0.1:2", "--stats",
                         str(stats)], "already exists")):
        out = papf("link", *args, timeout=60)
        assert out.returncode == 2 and says in out.stderr, out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
    assert stats.read_text() == "mine"


def test_papf_link_refuses_a_taken_port_with_one_line():
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        out = papf("link", "--listen", f"tcp/127.0.0.1:{port}", "--to", "tcp/127.0.0.1:2",
                   timeout=60)
    assert out.returncode == 2 and "cannot listen there" in out.stderr, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
