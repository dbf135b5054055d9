"""papf bench fleet-chain: a fleet cycle's phases from the arrival times in a recording."""

from __future__ import annotations

import csv

import pytest
from mcap.writer import Writer

from bench import bench_fleet_chain as fleet_chain
from tests.support.cli import papf

MS = 1_000_000


def write(path, samples):
    """``samples``: (topic, sim stamp [ns], arrival [ns])."""
    with path.open("wb") as fh:
        w = Writer(fh)
        w.start()
        schema = w.register_schema(name="x", encoding="", data=b"")
        channels = {}
        for topic, stamp, wall in samples:
            if topic not in channels:
                channels[topic] = w.register_channel(topic=topic, message_encoding="msgpack",
                                                     schema_id=schema)
            w.add_message(channels[topic], log_time=stamp, publish_time=wall, data=b"")
        w.finish()


def cycle(t_s: int, start_ms: int):
    """Two robots' instant at ``t_s``: burst from ``start_ms``, scans at +4/+6, commands +7/+9."""
    t, s = t_s * 10**9, start_ms * MS
    return [("r1/sim/bodies", t, s), ("r2/sim/bodies", t, s + MS), ("r2/clock", t, s + 2 * MS),
            ("r1/scan", t, s + 4 * MS), ("r2/scan", t, s + 6 * MS),
            ("r1/cmd_vel", t, s + 7 * MS), ("r2/cmd_vel", t, s + 9 * MS)]


def test_phases_of_each_instant_after_its_burst(tmp_path):
    path = tmp_path / "run.mcap"
    write(path, cycle(0, 0) + cycle(1, 100) + cycle(2, 120) + cycle(3, 150))
    out = fleet_chain.phases(fleet_chain.arrivals(path), 10**9)   # from 1 s: instants 1 and 2
    assert out["burst out"] == [2.0, 2.0] and out["first scan"] == [4.0, 4.0]
    assert out["last scan"] == [6.0, 6.0] and out["last cmd_vel"] == [9.0, 9.0]
    assert out["next burst"] == [20.0, 30.0]
    fleet_chain.main([str(path), "--label", "a", "--csv", str(tmp_path / "c.csv")])
    rows = list(csv.DictReader((tmp_path / "c.csv").open()))
    assert {r["phase"]: r["median_ms"] for r in rows}["next burst"] == "25.0"
    assert all(r["label"] == "a" and r["instants"] == "2" for r in rows)


def test_a_run_without_a_fleet_is_refused_in_one_line(tmp_path, capsys):
    path = tmp_path / "one.mcap"
    write(path, [("rosbot/scan", 2 * 10**9, 5)])
    with pytest.raises(SystemExit) as exc:
        fleet_chain.main([str(path)])
    assert exc.value.code == 2 and "no lockstep fleet instants" in capsys.readouterr().err


def test_what_is_not_a_recording_or_a_table_is_one_line(tmp_path):
    (tmp_path / "notes.mcap").write_text("hello\n")
    p = papf("bench", "fleet-chain", tmp_path / "notes.mcap")
    assert p.returncode == 2 and "not an MCAP file" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    path = tmp_path / "run.mcap"
    write(path, cycle(1, 0) + cycle(2, 30))
    p = papf("bench", "fleet-chain", path, "--csv", tmp_path / "missing" / "c.csv")
    assert p.returncode == 2 and "does not exist" in p.stderr and p.stdout == "", p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
