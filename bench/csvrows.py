"""The benchmarks' CSV output: rows appended under one header, or one label's rows replaced."""

from __future__ import annotations

import csv
from collections.abc import Iterable, Sequence
from pathlib import Path


def write_rows(path: Path, fields: Sequence[str], rows: Iterable[dict], append: bool = False) -> None:
    """Write ``rows`` (keys beyond ``fields`` ignored, missing ones empty) to the CSV at ``path``;
    ``append``: after the rows already there (the header only when the file is new or empty)."""
    new = not (append and path.exists() and path.stat().st_size)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w" if new else "a", newline="") as fh:
        out = csv.DictWriter(fh, list(fields), restval="", extrasaction="ignore")
        if new:
            out.writeheader()
        out.writerows(rows)


def replace_label(path: Path, fields: Sequence[str], label: str, rows: Iterable[dict]) -> None:
    """``rows`` (each given the column ``label``) replace the rows of that label in ``path``;
    other labels' rows stay, in their order (e.g. alternated before/after rounds)."""
    kept = []
    if path.exists():
        with path.open(newline="") as fh:
            kept = [r for r in csv.DictReader(fh) if r.get("label", "") != label]
    write_rows(path, fields, kept + [{**r, "label": label} for r in rows])
