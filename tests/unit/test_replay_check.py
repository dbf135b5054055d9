"""papf.experiments.replay_check reads a track file on its own (not through the world loader
it checks) and finds a replayed person out of place or shown while absent."""

from __future__ import annotations

import pytest

from papf.experiments.replay_check import position, read_tracks


def test_its_own_reading_of_the_file(tmp_path):
    f = tmp_path / "t.txt"
    f.write_text("0\t1\t0.0\t0.0\n10\t1\t1.0\t2.0\n10\t2\t5.0\t5.0\n20\t2\t6.0\t5.0\n")
    a, b = read_tracks(f, fps=25.0, from_s=0.0)
    assert position(a, 0.2) == pytest.approx((0.5, 1.0))     # linear between rows
    assert position(a, 0.5) is None and position(b, 0.3) is None   # outside first..last row
    assert position(b, 0.8) == pytest.approx((6.0, 5.0))
    (late,) = read_tracks(f, fps=25.0, from_s=0.5)              # person 1 gone before 0.5 s
    assert late[0][0] == pytest.approx(-0.1)
