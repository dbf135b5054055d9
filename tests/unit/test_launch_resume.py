"""A laptop that comes back to a running robot (papf/launch/resume.py): it must say what it wants."""

from __future__ import annotations

import pytest

from common.errors import ConfigError
from papf.launch.resume import Journal, RobotRun, decide, write_journal

RUN, RUN2 = bytes.fromhex("11" * 8), bytes.fromhex("22" * 8)


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
