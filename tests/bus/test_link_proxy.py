"""papf link between two Zenoh routers, in-process: the delay a subscriber sees, a stall
outage (nothing passes, nothing lost, TCP's retry after it), a reset outage (connections
reset, Zenoh reconnects)."""

from __future__ import annotations

import asyncio
import threading
import time
from contextlib import contextmanager

import zenoh

from common.transport import zenoh_config
from papf.launch.supervisor import free_port, wait_port
from papf.link.proxy import Endpoints, LinkEmulator
from papf.link.schedule import Outage, resume_after
from papf.link.spec import parse_spec

KEY = "linktest/x"


@contextmanager
def link_between(spec_text: str, robot_endpoint: str):
    """The emulator in a thread of its own (its asyncio loop), listening on a free port."""
    port = free_port()
    to = robot_endpoint.removeprefix("tcp/").rsplit(":", 1)
    emu = LinkEmulator(parse_spec(spec_text), Endpoints(("127.0.0.1", port), (to[0], int(to[1]))),
                       say=lambda text: None)
    loop = asyncio.new_event_loop()
    stop = asyncio.Event()
    thread = threading.Thread(target=loop.run_until_complete, args=(emu.serve(stop),), daemon=True)
    thread.start()
    assert wait_port(port, 15.0)
    try:
        yield emu, f"tcp/127.0.0.1:{port}"
    finally:
        loop.call_soon_threadsafe(stop.set)
        thread.join(15.0)


@contextmanager
def laptop_router(link_endpoint: str):
    """A router of the laptop's, joined to the robot's through the link; a subscriber on it
    that keeps (arrival monotonic s, payload)."""
    got: list[tuple[float, bytes]] = []
    conf = zenoh_config("router", connect=[link_endpoint], listen=[f"tcp/127.0.0.1:{free_port()}"],
                        scout_delay_ms=0)
    with zenoh.open(conf) as s:
        sub = s.declare_subscriber(KEY, lambda x: got.append((time.monotonic(),
                                                              x.payload.to_bytes())))
        yield got
        sub.undeclare()


def _until(pred, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


def _first_through(pub, got) -> None:
    """Publish until the laptop's subscriber hears one (the routers have met)."""
    assert _until(lambda: (pub.put(b"hello"), bool(got))[1], 60.0), "nothing crossed the link"


def test_a_subscriber_across_the_link_sees_its_one_way_delay(router, session):
    with link_between("delay=100", router) as (emu, ep), laptop_router(ep) as got:
        pub = session.declare_publisher(KEY)
        _first_through(pub, got)
        time.sleep(0.5)    # the last hellos are through
        delays = []
        for i in range(5):
            t = time.monotonic()
            pub.put(f"d{i}".encode())
            assert _until(lambda i=i: any(p == f"d{i}".encode() for _, p in got), 10.0)
            delays.append(next(a for a, p in got if p == f"d{i}".encode()) - t)
    assert min(delays) >= 0.1 - 0.002           # never faster than the link
    assert sorted(delays)[2] < 0.1 + 0.1         # the median: the emulator adds little
    assert emu.stats.directions["back"].chunks > 0 and emu.stats.connections >= 1


def test_a_stall_outage_holds_everything_and_loses_nothing(router, session):
    spec = "delay=5,outage=1.5@4"
    with link_between(spec, router) as (emu, ep), laptop_router(ep) as got:
        pub = session.declare_publisher(KEY)
        _first_through(pub, got)
        t0 = emu.outages.origin
        assert time.monotonic() < t0 + 3.5, "the routers took too long to meet for this test"
        sent = 0
        while time.monotonic() < t0 + 7.0:
            pub.put(f"n{sent}".encode())
            sent += 1
            time.sleep(0.02)
        assert _until(lambda: sum(p.startswith(b"n") for _, p in got) == sent, 15.0)
    resume = t0 + resume_after(Outage(4.0, 5.5), emu.dirs["back"].rto_s)
    arrivals = [t for t, p in got if p.startswith(b"n")]
    assert not [t for t in arrivals if t0 + 4.0 + 0.01 < t < resume]   # nothing passed
    assert [t for t in arrivals if t > resume]                          # then it did
    numbers = [int(p[1:]) for _, p in got if p.startswith(b"n")]
    assert numbers == list(range(sent))                                 # in order, all of it
    assert len(emu.events) == 1 and emu.events[0]["mode"] == "stall"


def test_a_reset_outage_resets_the_connection_and_zenoh_comes_back(router, session):
    with link_between("delay=5,outage=2@4,outage_mode=reset", router) as (emu, ep), \
            laptop_router(ep) as got:
        pub = session.declare_publisher(KEY)
        _first_through(pub, got)
        t0 = emu.outages.origin
        assert _until(lambda: time.monotonic() > t0 + 6.0, 10.0)
        n = len(got)
        assert _until(lambda: (pub.put(b"after"), len(got) > n)[1], 60.0), "no reconnection"
    assert emu.stats.resets >= 1
    assert not [t for t, _ in got if t0 + 4.0 + 0.01 < t < t0 + 6.0]
