"""Issue 20, second round, over a real router: ``papf topic echo`` under a flood of large
messages keeps its memory bounded and says what it dropped; keys and node names a peer
chose are printed escaped."""

from __future__ import annotations

import threading
import time

import zenoh

from common.transport import zenoh_config
from papf.bus import topics
from schemas import Keys

EVIL = "\x1b]0;owned\x07\x1b[2J"


def test_echo_under_a_flood_of_large_messages_stays_bounded(router, session):
    """A peer puts 1 MB messages as fast as it can while the printer is slow."""
    inbox = topics.Inbox(session, "flood/**", max_items=50, max_bytes=8 * 1024 * 1024)
    stop, peak = threading.Event(), {"items": 0, "bytes": 0}

    def flood():
        with zenoh.open(zenoh_config("client", [router])) as s:
            payload = b"\x00" * (1024 * 1024)
            for _ in range(300):
                s.put("flood/big", payload)
        stop.set()

    t = threading.Thread(target=flood, daemon=True)
    t.start()
    try:
        while not stop.is_set() or len(inbox):
            peak["items"] = max(peak["items"], len(inbox))
            peak["bytes"] = max(peak["bytes"], inbox._bytes)
            if inbox.get(0.05) is not None:
                time.sleep(0.02)           # a slow terminal
    finally:
        t.join(30)
        inbox.close()
    assert peak["items"] <= 50 and peak["bytes"] <= 8 * 1024 * 1024
    assert inbox.dropped > 0


def test_topic_list_shows_a_peers_escape_sequences_never_runs_them(router, session):
    keys = Keys("rosbot")
    lines: list[str] = []
    with zenoh.open(zenoh_config("client", [router])) as s:
        token = s.liveliness().declare_token(keys.alive(f"{EVIL}node"))
        pub_key = f"rosbot/{EVIL}topic"

        def put_some():
            for _ in range(20):
                s.put(pub_key, b"\x80")
                time.sleep(0.02)

        t = threading.Thread(target=put_some, daemon=True)
        t.start()
        topics.topic_list(session, keys, 0.5, lines.append)
        t.join(5)
        token.undeclare()
    text = "\n".join(lines)
    assert "\x1b" not in text and "\x07" not in text
    assert "\\x1b]0;owned" in text      # shown, escaped: the node name and the key
