"""The recording tools on hostile input (nodes/recorder/, papf/recording/): existing files, any
number of keys, decompression bombs, corrupted bytes, FIFOs, missing directories, full disks,
a flood on one key, a peer's escape sequences. Beside tests/unit/test_recorder.py (docs/architecture.md, "Tests")."""

from __future__ import annotations

import json
import os
import random

import lz4.frame
import pytest
import zstandard
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.records import Chunk

from common.errors import RecordingError
from common.outfiles import OutputError
from nodes.recorder.budget import QUEUE_FULL, Budget
from nodes.recorder.writer import RunWriter
from papf.recording import iter_messages, recover
from papf.recording.bounds import MAX_CHUNK_BYTES, check_chunk
from papf.recording.reader import Recording
from papf.recording.scan import scan_file
from tests.conftest import tiny_disk_free
from tests.support.cli import papf
from tests.support.recordings import ODOM_RUN_N, odom_at, write_odom_recording

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])
N = ODOM_RUN_N


def test_papf_info_shows_a_recorded_peers_escape_sequences_never_runs_them(tmp_path, capsys):
    from nodes.recorder.writer import RunWriter
    from papf.cli import main
    from schemas import Twist

    path = tmp_path / "r.mcap"
    with RunWriter(path, {"world": "\x1b]0;owned\x07", "note": "\x1b[2J" + "n" * 5000}) as w:
        w.write("rosbot/cmd_vel", Twist(stamp_ns=1, v=0.1, w=0.0).to_bytes())
        w.write("rosbot/\x1b[2J" + "k" * 100_000, b"\x80", 2)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\\x1b[2J" in out
    assert max(len(line) for line in out.splitlines()) < 1000   # a 100 KB key: one short line


def test_the_recorder_refuses_an_existing_recording(tmp_path):
    path = tmp_path / "a.mcap"
    path.write_bytes(b"the user's recording")
    with pytest.raises(OutputError):
        RunWriter(path)
    assert path.read_bytes() == b"the user's recording"
    RunWriter(path, force=True).close()
    assert Recording(path).counts() == {}


@SETTINGS
@given(n_keys=st.integers(1, 400), cap=st.integers(1, 50))
def test_any_number_of_keys_leaves_a_complete_recording(tmp_path_factory, n_keys, cap):
    path = tmp_path_factory.mktemp("rec") / "k.mcap"
    w = RunWriter(path, max_channels=cap)
    for i in range(n_keys):
        w.write(f"peer/k{i}", b"\x01", receive_ns=i)
        w.write(f"peer/k{i}", b"\x02", receive_ns=i)
    w.close()
    assert w.stats.channels == min(n_keys, cap)
    assert w.stats.dropped == 2 * max(0, n_keys - cap)
    with Recording(path) as rec:   # footer and summary present
        assert sum(rec.counts().values()) == 2 * min(n_keys, cap)
        if n_keys > cap:
            assert rec.metadata["dropped"]["messages"] == str(2 * (n_keys - cap))


def test_sixty_five_thousand_keys_do_not_overflow_the_channel_ids(tmp_path):
    path = tmp_path / "many.mcap"
    with RunWriter(path) as w:
        for i in range(70_000):
            w.write(f"x/{i}", b"", receive_ns=i)
    with open(path, "rb") as f:
        assert make_reader(f).get_summary() is not None


def _bomb_chunk(compression: str, declared: int) -> Chunk:
    zeros = b"\0" * (MAX_CHUNK_BYTES + 1024)
    data = (zstandard.ZstdCompressor().compress(zeros) if compression == "zstd"
            else lz4.frame.compress(zeros, store_size=False))
    return _chunk(compression, declared, data)


def _chunk(compression: str, declared: int, data: bytes) -> Chunk:
    return Chunk(message_start_time=0, message_end_time=0, uncompressed_size=declared,
                 uncompressed_crc=0, compression=compression, data=data)


@pytest.mark.parametrize("compression,declared", [("zstd", 10), ("zstd", 2**40), ("lz4", 10),
                                                  ("", 2**40)])
def test_a_chunk_that_would_decompress_past_the_bound_is_refused_before(compression, declared):
    chunk = _bomb_chunk(compression, declared) if compression else _chunk("", declared, b"")
    with pytest.raises(RecordingError, match="more than"):
        check_chunk(chunk, "bomb.mcap")


@SETTINGS
@given(st.binary(min_size=1, max_size=4000))
def test_ordinary_chunks_pass_the_bound(payload):
    for compression, data in (("zstd", zstandard.ZstdCompressor().compress(payload)),
                              ("lz4", lz4.frame.compress(payload)), ("", payload)):
        check_chunk(_chunk(compression, len(payload), data), "ok.mcap")


def test_every_reader_refuses_a_decompression_bomb_before_allocating(tmp_path, monkeypatch):
    """A 50 KB file whose one zstd chunk claims 1 GiB: Recording (info, report, replay,
    export, animate) refuses it in one line; recover skips it as a damaged chunk."""
    from mcap.writer import CompressionType, Writer

    from papf.recording.recover import recover

    bomb = zstandard.ZstdCompressor(level=3).compress(b"\0" * (1 << 30))
    path = tmp_path / "bomb.mcap"
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD)
        w.start(profile="papf", library="test")
        ch = w.register_channel("rosbot/odom", "msgpack", 0)
        w.add_message(ch, 1, b"x", 1)
        monkeypatch.setattr(zstandard.ZstdCompressor, "compress", lambda self, data: bomb)
        w.finish()
    monkeypatch.undo()
    assert path.stat().st_size < 100_000
    with pytest.raises(RecordingError, match="would decompress to 1,073,741,824 bytes"):
        Recording(path)
    stats = recover(path, tmp_path / "fixed.mcap")
    assert stats.scan.bad_chunks == 1 and stats.messages == 0


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


def test_scan_file_counts_intact_messages(recording):
    stats, n = scan_file(recording)
    assert n == N and not stats.damaged and stats.expected_messages == N


def test_a_flood_on_one_key_cannot_starve_another():
    budget = Budget(queued_max=1_000_000, clock=lambda: 0.0)
    flood = [budget.admit("rosbot/scan", 100_000) for _ in range(20)]
    assert QUEUE_FULL in flood
    assert all(budget.admit("rosbot/odom", 100) == "" for _ in range(50))
    assert budget.counts()["rosbot/scan"][QUEUE_FULL] == flood.count(QUEUE_FULL)
