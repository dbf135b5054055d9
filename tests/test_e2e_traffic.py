"""Moving obstacles through the whole stack: tracks from the tracker node, same seed -> same run."""

import pytest

from papf.recording.reader import iter_messages
from schemas.messages import Objects
from tests.e2e import papf_run

pytestmark = pytest.mark.e2e


def objects_of(path):
    return [msg for _key, msg, _t in iter_messages(path, "rosbot/objects")]


def test_moving_traffic_with_the_tracker_repeats_exactly(tmp_path):
    # IAPF steers by the tracks, so the tracker's output shapes the trajectory
    runs = [papf_run("--world", "road-cut-in", "--planner", "iapf", "--objects", "tracker",
                     "--seed", "3", "--timeout", "12", "--record", str(tmp_path / f"{i}.mcap"))
            for i in range(2)]
    (_, a, err_a), (_, b, err_b) = runs
    assert a is not None and b is not None, (err_a[-2000:], err_b[-2000:])
    a.pop("wall_time_s"), b.pop("wall_time_s")
    assert a == b and a["outcome"] == "timeout" and a["collisions"] == 0
    # the tracker's output, message by message, up to the run's end (after it the nodes
    # may publish a few more messages before they stop, as many as timing allows)
    end_ns = int(a["sim_time_s"] * 1e9)
    tracks_a, tracks_b = ([m for m in objects_of(tmp_path / f"{i}.mcap") if m.stamp_ns < end_ns]
                          for i in range(2))
    assert len(tracks_a) >= 100 and all(isinstance(m, Objects) for m in tracks_a)
    assert tracks_a == tracks_b
    seen = [m for m in tracks_a if m.tracks]
    assert seen and seen[-1].tracks[0].vx > 0.3     # the cut-in car, 0.5 m/s along +x


def test_truth_objects_are_published_with_each_scan(tmp_path):
    code, res, err = papf_run("--world", "road-slow-leader", "--planner", "apf", "--objects",
                              "truth", "--timeout", "3", "--record", str(tmp_path / "t.mcap"))
    assert res is not None, err[-2000:]
    # up to the run's end: the scan at the end stamp may be recorded without its objects
    # (the nodes stop as timing allows), as in the test above
    end_ns = int(res["sim_time_s"] * 1e9)
    stamps = {m.stamp_ns for m in objects_of(tmp_path / "t.mcap") if m.stamp_ns < end_ns}
    scans = {m.stamp_ns for _k, m, _t in iter_messages(tmp_path / "t.mcap", "rosbot/scan")
             if m.stamp_ns < end_ns}
    assert scans and stamps == scans
    last = objects_of(tmp_path / "t.mcap")[-1]
    (leader,) = last.tracks
    assert last.source == "truth" and leader.vx == pytest.approx(0.1)
    assert leader.x == pytest.approx(1.2 + 0.1 * last.stamp_ns / 1e9)
