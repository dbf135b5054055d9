"""The benchmarks' CSV output: rows appended under one header, or one label's rows replaced.

These CSVs are append-only by design (a benchmark adds its rows to the table of earlier
rounds), so an existing file is written again — but only when it is that table: a regular
file (never through a symlink) whose header is the benchmark's. Anything else (a recording,
a user's file, another table, a directory) is refused in one line (``OutputError``, exit 2),
and a new or rewritten file goes beside and is renamed into place (:mod:`common.outfiles`).
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from common.outfiles import OutputError, check_output, output


def _header(fields: Sequence[str]) -> str:
    buf = io.StringIO()
    csv.writer(buf).writerow(list(fields))
    return buf.getvalue().rstrip("\r\n")


def check_csv(path: Path, fields: Sequence[str]) -> bool:
    """Whether ``path`` holds rows already (True) or is new or empty (False); OutputError
    unless it is a regular file whose first line is the header of ``fields``."""
    path = Path(path)
    if not os.path.lexists(path):
        check_output(path)   # its directory exists; nothing is there
        return False
    if path.is_symlink() or not path.is_file():
        what = "a symlink" if path.is_symlink() else "a directory" if path.is_dir() else "not a file"
        raise OutputError(f"{path}: is {what}; name a CSV file of this benchmark or a new one")
    if path.stat().st_size == 0:
        return False
    with path.open("rb") as fh:
        first = fh.readline(64 * 1024).decode("utf-8", "replace").rstrip("\r\n")
    if first != _header(fields):
        raise OutputError(f"{path}: exists and is not this benchmark's CSV (its first line is not "
                          f"{_header(fields)[:80]!r}); name a new file")
    return True


def write_rows(path: Path, fields: Sequence[str], rows: Iterable[dict], append: bool = False) -> None:
    """Write ``rows`` (keys beyond ``fields`` ignored, missing ones empty) to the CSV at ``path``;
    ``append``: after the rows already there (the header only when the file is new or empty).
    An existing ``path`` must be this table (:func:`check_csv`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    has_rows = check_csv(path, fields)
    if append and has_rows:
        flags = os.O_WRONLY | os.O_APPEND | getattr(os, "O_NOFOLLOW", 0)
        with os.fdopen(os.open(path, flags), "a", newline="") as fh:
            csv.DictWriter(fh, list(fields), restval="", extrasaction="ignore").writerows(rows)
        return
    with output(path, force=True) as tmp, tmp.open("w", newline="") as fh:
        out = csv.DictWriter(fh, list(fields), restval="", extrasaction="ignore")
        out.writeheader()
        out.writerows(rows)


def replace_label(path: Path, fields: Sequence[str], label: str, rows: Iterable[dict]) -> None:
    """``rows`` (each given the column ``label``) replace the rows of that label in ``path``;
    other labels' rows stay, in their order (e.g. alternated before/after rounds)."""
    kept = []
    if check_csv(path, fields):
        with Path(path).open(newline="") as fh:
            kept = [r for r in csv.DictReader(fh) if r.get("label", "") != label]
    write_rows(path, fields, kept + [{**r, "label": label} for r in rows])


def emit(rows: list[dict], row: dict, label: str | None) -> None:
    """A benchmark's row as it comes: printed as one JSON line (progress on long work), and
    kept in ``rows`` under ``label`` for :func:`replace_label`."""
    print(json.dumps(row), flush=True)
    rows.append({"label": label or "", **row})
