"""The run's key on this host (common/runauth.py): readable by its user only, never through a
directory another user made or linked, one launch per namespace, signed requests that a tamper breaks."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common import runauth
from papf.launch.outcome import RunMonitor
from schemas import Goal

KEY = bytes.fromhex(runauth.new_key())


def test_a_key_directory_another_user_made_or_linked_is_not_used(tmp_path, monkeypatch):
    import os

    from common import runauth

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    elsewhere = tmp_path / "attacker"
    elsewhere.mkdir()
    (tmp_path / f"papf-{os.getuid()}").symlink_to(elsewhere)
    (elsewhere / "rosbot.key").write_text("00" * 32 + " 1\n")
    with pytest.raises(runauth.KeyDirError, match="not a directory of your own"):
        runauth.publish_key("rosbot", runauth.new_key())
    assert runauth.read_key("rosbot") is None
    assert (elsewhere / "rosbot.key").read_text() == "00" * 32 + " 1\n"


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


def test_a_launched_sessions_key_is_readable_by_its_user_only(tmp_path, monkeypatch):
    """`papf goal` on the same host signs with the session's key; nobody else gets it."""
    import os
    import stat

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    key = runauth.new_key()
    path = runauth.publish_key("lab/r1", key)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    assert stat.S_IMODE(os.stat(path.parent).st_mode) == 0o700
    assert runauth.read_key("lab/r1") == bytes.fromhex(key)
    m = RunMonitor(timeout_s=100, goal=(5.0, 0.0, 0.1))
    m.on_goal(runauth.sign(Goal(stamp_ns=0, x=1.5, y=1.0), bytes.fromhex(key)))
    assert m.goal == (1.5, 1.0, 0.1)
    runauth.withdraw_key("lab/r1", key)
    assert runauth.read_key("lab/r1") is None
