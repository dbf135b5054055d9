"""Issue "trust no input", items 11 and 12 (and the recover half of 5): the recording
tools on corrupted files, FIFOs, missing directories, full disks, bad rates and no router."""

from __future__ import annotations

import json
import os
import random

import pytest

from common.errors import RecordingError
from papf.recording import iter_messages, recover
from papf.recording.scan import scan_file
from tests.conftest import tiny_disk_free
from tests.support.cli import papf
from tests.support.recordings import ODOM_RUN_N, odom_at, write_odom_recording, write_ros_topics

N = ODOM_RUN_N


@pytest.fixture
def recording(tmp_path):
    return write_odom_recording(tmp_path / "run.mcap")


def _flip(src, dst, n, seed=10):
    data = bytearray(src.read_bytes())
    rng = random.Random(seed)
    for _ in range(n):
        data[rng.randrange(200, len(data) - 300)] ^= 0xFF
    dst.write_bytes(bytes(data))


def test_recover_says_what_byte_flips_lost(recording, tmp_path):
    broken, fixed = tmp_path / "flipped.mcap", tmp_path / "fixed.mcap"
    _flip(recording, broken, 6)
    p = papf("recover", "--json", broken, fixed)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["complete"] is False and out["skipped_chunks"] >= 1
    assert out["expected_messages"] == N
    assert out["messages"] + out["lost_messages"] == N and out["lost_messages"] > 0
    text = papf("recover", "--force", broken, fixed).stdout   # fixed exists: replaced only when told
    assert f"LOST {out['lost_messages']} messages" in text and "complete" not in text
    kept = list(iter_messages(fixed))
    assert len(kept) == out["messages"] and all(m.message == odom_at(round(m.message.stamp_ns
                                                / 20_000_000)) for m in kept)


def test_info_and_report_check_chunk_crcs(recording, tmp_path):
    broken = tmp_path / "flipped.mcap"
    _flip(recording, broken, 6)
    p = papf("info", broken)
    assert p.returncode == 2
    assert "is damaged" in p.stderr and "fail their CRC" in p.stderr and "papf recover" in p.stderr
    with pytest.raises(RecordingError, match="is damaged: a chunk fails its CRC"):
        list(iter_messages(broken))         # what report and replay read through
    assert papf("info", recording).returncode == 0


def test_recover_resynchronises_after_a_corrupted_first_record_length(recording, tmp_path):
    data = bytearray(recording.read_bytes())
    data[9:17] = (2**62).to_bytes(8, "little")       # the header record's length
    broken = tmp_path / "firstlen.mcap"
    broken.write_bytes(bytes(data))
    stats = recover(broken, tmp_path / "fixed.mcap")
    assert stats.messages == N and stats.scan.damaged_bytes > 0 and not stats.complete
    assert "LOST 0 messages" in stats.summary()


def test_resync_skips_damage_in_the_middle(recording, tmp_path):
    data = bytearray(recording.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 40] = os.urandom(40)
    broken = tmp_path / "mid.mcap"
    broken.write_bytes(bytes(data))
    stats = recover(broken, tmp_path / "fixed.mcap")
    assert 0 < stats.messages < N and stats.lost_messages == N - stats.messages


def test_info_and_recover_refuse_a_fifo_instead_of_blocking(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for args in (("info", fifo), ("recover", fifo, tmp_path / "x.mcap"), ("report", fifo)):
        p = papf(*args, timeout=30)
        assert p.returncode == 2 and "not a regular file" in p.stderr, (args, p.stderr)


def test_recover_and_report_into_a_missing_directory_are_one_line(recording, tmp_path):
    p = papf("recover", recording, tmp_path / "no" / "such" / "x.mcap")
    assert p.returncode == 2 and "does not exist" in p.stderr and "Traceback" not in p.stderr
    p = papf("report", recording, "--out", recording / "sub")     # under a file: impossible
    assert p.returncode == 2 and "cannot create the report directory" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
    p = papf("report", recording, "--out", tmp_path / "new" / "dir")  # report creates it
    assert p.returncode == 0 and (tmp_path / "new" / "dir" / "report.md").is_file()


def test_recover_into_a_full_disk_leaves_no_empty_output(recording, tiny_disk):
    (tiny_disk / "filler").write_bytes(b"x" * (tiny_disk_free(tiny_disk) - 2048))
    with pytest.raises(RecordingError, match="No space left on device; nothing was written"):
        recover(recording, tiny_disk / "fixed.mcap")
    assert sorted(p.name for p in tiny_disk.iterdir()) == ["filler"]
    p = papf("recover", recording, tiny_disk / "fixed.mcap")
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in tiny_disk.iterdir()) == ["filler"]


# -- replay ----------------------------------------------------------------------------------
@pytest.fixture
def ros_recording(tmp_path):
    return write_ros_topics(tmp_path / "ros.mcap")


def test_replay_bad_rate_and_no_router_are_one_line(ros_recording):
    for args in (("--rate", "nan"), ("--rate", "inf"), ("--rate", "-1"),
                 ("--connect", "tcp/127.0.0.1:1")):
        p = papf("replay", ros_recording, *args)
        assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, (args, p.stderr)


def test_scan_file_counts_intact_messages(recording):
    stats, n = scan_file(recording)
    assert n == N and not stats.damaged and stats.expected_messages == N
