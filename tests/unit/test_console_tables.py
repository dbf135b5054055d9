"""Tables that fit (papf/console/tables.py): piped, one line a row; on a narrow terminal, whole
values one per line; the report's markdown table as a table."""

from __future__ import annotations

import io


def _wide_table():
    from rich.table import Table

    t = Table(title="robots")
    for col in ("robot", "planner", "outcome", "time s", "path m", "mAh", "coll.", "sep. m",
                "disc. s", "reason"):
        t.add_column(col)
    t.add_row("r1", "wang-apf", "stagnated", "49.18", "4.91", "11.79", "0", "0.552", "0.00",
              "no progress for 20 s within 1.5 m of the goal")
    return t


def test_a_piped_table_is_one_line_a_row_never_wrapped_or_cut(monkeypatch):
    from rich.console import Console

    from papf.console.tables import print_table

    monkeypatch.setenv("COLUMNS", "80")
    out = io.StringIO()
    print_table(_wide_table(), Console(file=out))
    lines = out.getvalue().splitlines()
    row = next(line for line in lines if "r1" in line)
    assert "no progress for 20 s within 1.5 m of the goal" in row and "wang-apf" in row
    assert "…" not in out.getvalue() and len(row) > 80
    assert "\x1b" not in out.getvalue()


def test_a_narrow_terminal_gets_whole_values_one_per_line():
    from rich.console import Console

    from papf.console.tables import print_table

    out = io.StringIO()
    print_table(_wide_table(), Console(file=out, force_terminal=True, width=80, color_system=None))
    text = out.getvalue()
    assert all(len(line) <= 80 for line in text.splitlines())
    assert "robot: r1" in text and "  planner: wang-apf" in text
    assert "  reason:  no progress for 20 s within 1.5 m of the goal" in text
    out = io.StringIO()   # a table that fits stays a table
    small = _wide_table()
    small.columns = small.columns[:3]
    print_table(small, Console(file=out, force_terminal=True, width=80, color_system=None))
    assert "┃ robot ┃ planner  ┃ outcome   ┃" in out.getvalue()


def test_the_reports_markdown_table_becomes_a_table_that_fits():
    from papf.console.tables import markdown_table

    t = markdown_table("| planner | charge [mAh, motor model] |\n|---|---|\n| pa\\|pf | 23.95 |\n")
    assert [c.header.plain for c in t.columns] == ["planner", "charge [mAh, motor model]"]
    assert [c._cells[0].plain for c in t.columns] == ["pa|pf", "23.95"]
    assert markdown_table("no table here") is None
