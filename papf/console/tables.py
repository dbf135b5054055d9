"""Tables that fit: never a cell wrapped or cut in the middle, on a terminal or piped.

:func:`print_table` prints a rich ``Table``:

- on a terminal wide enough for it: as it is;
- on a terminal too narrow (80 columns, a split pane): one block per row, ``header: value``
  a line, so every value stays whole and readable;
- piped (a file, ``| less``, ``| grep``): at its natural width, never wrapped at rich's 80
  columns, so a row is one line a script can read.

:func:`markdown_table` turns a Markdown pipe table (the report's) into a rich ``Table``, so
``papf report`` shows it the same way on a terminal; piped, the Markdown is printed as is.
"""

from __future__ import annotations

import re

from rich.console import Console
from rich.table import Table
from rich.text import Text

_CELL_SPLIT = re.compile(r"(?<!\\)\|")


def natural_width(table: Table, console: Console) -> int:
    """The columns ``table`` takes with nothing wrapped (rich's own measure of it)."""
    wide = Console(width=100_000, file=console.file, color_system=None)
    return wide.measure(table).maximum


def print_table(table: Table, console: Console | None = None) -> None:
    """``table`` on ``console`` (default: stdout), fitted as the module doc says."""
    console = console or Console()
    width = natural_width(table, console)
    if not console.is_terminal:
        Console(file=console.file, width=width, color_system=None, highlight=False,
                soft_wrap=False).print(table)
    elif width <= console.width:
        console.print(table)
    else:
        console.print(compact(table))


def compact(table: Table) -> Text:
    """``table`` as one block per row, ``header: value`` a line (the first column heads the
    block): what a terminal too narrow for the table shows."""
    headers = [_plain(c.header) for c in table.columns]
    cells = [[_plain(cell) for cell in c._cells] for c in table.columns]
    out = Text()
    if table.title:
        out.append(_plain(table.title) + "\n", style="bold")
    rows = [[col[r] if r < len(col) else "" for col in cells]
            for r in range(max((len(c) for c in cells), default=0))]
    if not table.show_header:   # a key-value table (a run's summary): "key: value" lines
        for key, *values in rows:
            out.append(f"{key}: {'  '.join(values)}\n")
        return out
    pad = max((len(h) for h in headers[1:]), default=0)
    for first, *values in rows:
        out.append(f"{headers[0]}: {first}\n" if headers[0] else f"{first}\n", style="bold")
        for header, value in zip(headers[1:], values, strict=True):
            out.append(f"  {header + ':':<{pad + 1}} {value}\n")
    return out


def _plain(cell) -> str:
    """A cell's text without rich markup."""
    if isinstance(cell, Text):
        return cell.plain
    return Text.from_markup(str(cell)).plain


def markdown_table(text: str, title: str | None = None) -> Table | None:
    """The first Markdown pipe table in ``text`` as a rich ``Table`` (cells as text, never
    markup), or None when ``text`` holds none."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip().startswith("|")]
    if len(lines) < 2 or not re.fullmatch(r"\|(\s*:?-+:?\s*\|)+", lines[1].replace(" ", "")):
        return None
    def cells(line: str) -> list[str]:
        return [c.strip().replace("\\|", "|") for c in _CELL_SPLIT.split(line.strip("|"))]
    table = Table(title=title)
    head = cells(lines[0])
    for i, h in enumerate(head):
        table.add_column(Text(h), justify="left" if i == 0 else "right")
    for line in lines[2:]:
        row = cells(line)
        table.add_row(*(Text(c) for c in (row + [""] * len(head))[:len(head)]))
    return table
