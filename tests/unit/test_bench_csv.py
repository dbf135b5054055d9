"""The benchmarks' CSVs (bench/csvrows.py): appended only to their own table, never through a
symlink or into a directory, a foreign one refused before measuring."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

SETTINGS = settings(max_examples=60, deadline=None)


@SETTINGS
@given(st.binary(min_size=1, max_size=200))
def test_a_benchmark_csv_appends_only_to_its_own_table(tmp_path_factory, head):
    from bench.csvrows import write_rows
    from common.outfiles import OutputError

    d = tmp_path_factory.mktemp("csv")
    other = d / "other.csv"
    other.write_bytes(head)
    if head.split(b"\n")[0].rstrip(b"\r") != b"a,b":
        with pytest.raises(OutputError, match="not this benchmark's CSV"):
            write_rows(other, ("a", "b"), [{"a": 1, "b": 2}], append=True)
        assert other.read_bytes() == head


def test_a_benchmark_csv_never_writes_through_a_symlink_or_into_a_directory(tmp_path):
    from bench.csvrows import replace_label, write_rows
    from common.outfiles import OutputError

    ours = tmp_path / "ours.csv"
    write_rows(ours, ("a", "b"), [{"a": 1, "b": 2}], append=True)
    write_rows(ours, ("a", "b"), [{"a": 3, "b": 4}], append=True)
    assert ours.read_text().splitlines() == ["a,b", "1,2", "3,4"]
    link = tmp_path / "link.csv"
    link.symlink_to(ours)
    for path in (link, tmp_path):
        with pytest.raises(OutputError):
            write_rows(path, ("a", "b"), [{"a": 5}], append=True)
        with pytest.raises(OutputError):
            replace_label(path, ("a", "b", "label"), "x", [{"a": 5}])
    assert ours.read_text().splitlines() == ["a,b", "1,2", "3,4"]


def test_a_benchmark_refuses_a_foreign_csv_before_measuring(tmp_path, capsys):
    """Issue #35, output checks before work: every command that writes files checks them
    first (papf bench planner takes seconds to minutes before it writes its CSV)."""
    from papf.cli import main

    mine = tmp_path / "mine.csv"
    mine.write_text("the user's own table\n")
    assert main(["bench", "planner", "--csv", str(mine), "--cycles", "10"]) == 2
    out, err = capsys.readouterr()
    assert "is not this benchmark's CSV" in err
    assert out == ""   # no case measured (each prints its JSON line as it ends)
    assert mine.read_text() == "the user's own table\n"
