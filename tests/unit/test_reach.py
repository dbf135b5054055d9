"""A session that did not open says why: nothing there, or a router that refused our credentials."""

from __future__ import annotations

import socket

import pytest

from common.reach import accepts, session_error
from papf.launch.supervisor import free_port


@pytest.fixture
def listening():
    """A TCP port that accepts connections (as a router's does), and one where nothing listens."""
    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen(8)
        yield srv.getsockname()[1], free_port()


def test_a_port_that_accepts_is_a_router_that_refused_us(listening):
    up, down = listening
    assert accepts(f"tls/127.0.0.1:{up}") and not accepts(f"tls/127.0.0.1:{down}")
    exc = RuntimeError("Unable to connect to any of [...]! at /zenoh/src/net/runtime.rs:1")
    text = str(session_error(exc, [f"tls/127.0.0.1:{up}"], None, f"tls/127.0.0.1:{up}"))
    assert text.startswith(f"authentication failed at tls/127.0.0.1:{up}")
    assert "has none" in text and "--zenoh-config" in text and "stack running" not in text
    text = str(session_error(exc, [f"tls/127.0.0.1:{up}"], "laptop.json5", "x"))
    assert "refused the credentials of laptop.json5" in text
    text = str(session_error(exc, [f"tcp/127.0.0.1:{up}"], None, "x"))
    assert "asks for credentials" in text


def test_nothing_listening_is_no_stack(listening):
    _, down = listening
    exc = RuntimeError("Unable to connect to any of [...]!")
    text = str(session_error(exc, [f"tcp/127.0.0.1:{down}"], None, f"tcp/127.0.0.1:{down}"))
    assert text.startswith(f"cannot reach the bus at tcp/127.0.0.1:{down}")
    assert "is a stack running" in text and "authentication" not in text
    assert not accepts("udp/127.0.0.1:1") and not accepts("unixsock-stream//tmp/x")
