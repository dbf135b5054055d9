"""Issue 20, items 3, 4, 7: files we write never replace a user's file or an input, and
readers bound what they allocate (common/outfiles.py, nodes/recorder/writer.py,
papf/recording/bounds.py). Property-based: any content, any way of naming the same file."""

from __future__ import annotations

import os

import lz4.frame
import pytest
import zstandard
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.records import Chunk

from common.errors import RecordingError
from common.outfiles import OutputError, check_output, exclusive, output
from nodes.recorder.writer import RunWriter
from papf.recording.bounds import MAX_CHUNK_BYTES, check_chunk
from papf.recording.reader import Recording

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@SETTINGS
@given(old=st.binary(max_size=200), new=st.binary(max_size=200))
def test_an_existing_file_is_never_replaced_without_force(tmp_path, old, new):
    out = tmp_path / "a.mcap"
    out.write_bytes(old)
    with pytest.raises(OutputError, match="already exists; use --force"):
        with output(out) as tmp:
            tmp.write_bytes(new)
    assert out.read_bytes() == old
    with output(out, force=True) as tmp:
        tmp.write_bytes(new)
    assert out.read_bytes() == new
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mcap"]   # no temp file left


@pytest.mark.parametrize("how", ["hardlink", "symlink", "dotted"])
def test_an_input_is_refused_as_output_even_with_force(tmp_path, how):
    src = tmp_path / "in.mcap"
    src.write_bytes(b"recording")
    out = {"hardlink": tmp_path / "hard.mcap", "symlink": tmp_path / "d.gif",
           "dotted": tmp_path / "." / "in.mcap"}[how]
    if how == "hardlink":
        os.link(src, out)
    elif how == "symlink":
        out.symlink_to(src)
    for force in (False, True):
        with pytest.raises(OutputError, match="is the input"):
            check_output(out, [src], force)
    assert src.read_bytes() == b"recording"


def test_a_symlink_output_is_replaced_itself_never_its_target(tmp_path):
    target, link = tmp_path / "user.txt", tmp_path / "out.gif"
    target.write_text("the user's")
    link.symlink_to(target)
    with pytest.raises(OutputError, match="a symlink already exists"):
        check_output(link)
    with output(link, force=True) as tmp:
        tmp.write_bytes(b"GIF")
    assert target.read_text() == "the user's" and not link.is_symlink()
    assert link.read_bytes() == b"GIF"


def test_a_failed_write_leaves_the_old_file_and_no_temp(tmp_path):
    out = tmp_path / "x.png"
    out.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with output(out, force=True) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("figure failed")
    assert out.read_bytes() == b"old" and sorted(tmp_path.iterdir()) == [out]


def test_exclusive_never_follows_a_symlink(tmp_path):
    target, link = tmp_path / "t", tmp_path / "r.mcap"
    target.write_bytes(b"keep")
    link.symlink_to(target)
    with pytest.raises(OutputError):
        exclusive(link)
    with exclusive(link, force=True) as f:
        f.write(b"new")
    assert target.read_bytes() == b"keep" and link.read_bytes() == b"new"


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
