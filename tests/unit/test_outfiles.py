"""Files we write (common/outfiles.py) never replace a user's file or an input: refused unless
forced, an input never even forced, a symlink replaced itself never its target, no temp file
left, a JSONL trace appended only to JSON lines. Property-based: any content, any way of naming the same file."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common.outfiles import OutputError, check_output, exclusive, output

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.mark.skipif(__import__("os").geteuid() == 0, reason="root writes anywhere")
def test_an_output_in_a_read_only_directory_is_refused_before_the_work(tmp_path):
    from common.outfiles import OutputError, check_output

    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o555)
    try:
        with pytest.raises(OutputError, match="not writable"):
            check_output(d / "x.png")
    finally:
        d.chmod(0o755)


def test_a_jsonl_trace_appends_only_to_json_lines(tmp_path):
    from common.outfiles import OutputError, append_jsonl

    rec = tmp_path / "run.mcap"
    rec.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 100)
    link = tmp_path / "t.jsonl"
    link.symlink_to(tmp_path / "elsewhere.jsonl")
    for bad in (rec, link, tmp_path):
        with pytest.raises(OutputError):
            append_jsonl(bad)
    assert rec.read_bytes().startswith(b"\x89MCAP0") and not (tmp_path / "elsewhere.jsonl").exists()
    good = tmp_path / "trace.jsonl"
    for _ in range(2):
        with append_jsonl(good) as fh:
            fh.write('{"v": 1}\n')
    assert good.read_text() == '{"v": 1}\n{"v": 1}\n'


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
