"""Tables and numbers in the docs that come from committed CSVs (``make docs``, ``make docs-check``).

``render`` rewrites what lies between ``<!-- table ... -->`` / ``<!-- v ... -->`` markers
from the CSVs; ``check`` lists each place where the committed text differs. Used by
``make docs`` and ``make docs-check``; the markers' syntax: :func:`render`.
"""

from __future__ import annotations

import csv
import difflib
import re
import sys
from pathlib import Path

from common.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
TABLE = re.compile(r"(<!-- table (?P<spec>.*?) -->\n)(?P<body>.*?)(<!-- /table -->)", re.S)
VALUE = re.compile(r"(<!-- v (?P<spec>.*?) -->)(?P<body>.*?)(<!-- /v -->)", re.S)


def _parse(spec: str) -> tuple[str, list[tuple[str, str, str]], dict[str, str], int | None]:
    """A marker's spec: its CSV, columns (name, header, format), ``where`` pairs and
    ``first`` (how many matching rows a table keeps; None: all)."""
    parts = [p.strip() for p in spec.split("|")]
    cols, where, first = [], {}, None
    for part in parts[1:]:
        if re.fullmatch(r"first \d+", part):
            first = int(part.split()[1])
        elif part.startswith("where "):
            for pair in part[6:].split(","):
                k, _, v = pair.partition("=")
                where[k.strip()] = v.strip()
        elif part:
            name, _, fmt = part.partition(":")
            name, _, header = name.partition("=")
            cols.append((name.strip(), header.strip() or name.strip(), fmt.strip()))
    return parts[0], cols, where, first


def _rows(base: Path, file: str, where: dict[str, str]) -> tuple[list[str], list[dict]]:
    path = base / file
    try:
        with path.open(newline="") as fh:
            reader = csv.DictReader(fh)
            rows = list(reader)
            fields = list(reader.fieldnames or [])
    except OSError as exc:
        raise ConfigError(f"docs table: cannot read {path}: {exc}") from None
    bad = [k for k in where if k not in fields]
    if bad:
        raise ConfigError(f"docs table {file}: no column {bad}; columns: {fields}")
    return fields, [r for r in rows if all(r[k] == v for k, v in where.items())]


def _cell(value: str, fmt: str) -> str:
    if not fmt or value == "":
        return value
    try:
        return format(float(value), fmt)
    except ValueError:
        return value


def _table(base: Path, spec: str) -> str:
    file, cols, where, first = _parse(spec)
    fields, rows = _rows(base, file, where)
    rows = rows[:first]
    cols = cols or [(f, f, "") for f in fields]
    missing = [c[0] for c in cols if c[0] not in fields]
    if missing:
        raise ConfigError(f"docs table {file}: no column {missing}; columns: {fields}")
    out = ["| " + " | ".join(h for _n, h, _f in cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(_cell(r[n], f).replace("|", "\\|") for n, _h, f in cols) + " |"
            for r in rows]
    return "\n".join(out) + "\n"


def _value(base: Path, spec: str) -> str:
    file, cols, where, _first = _parse(spec)
    _fields, rows = _rows(base, file, where)
    if len(cols) != 1 or len(rows) != 1:
        raise ConfigError(f"docs value {spec!r}: needs one column and one matching row "
                          f"(got {len(cols)} column(s), {len(rows)} row(s))")
    name, _h, fmt = cols[0]
    if name not in rows[0]:
        raise ConfigError(f"docs value {spec!r}: no column {name!r}")
    return _cell(rows[0][name], fmt)


def render(text: str, base: Path) -> str:
    """``text`` with every marked table and value regenerated from its CSV.

    Convention (Markdown, invisible once rendered):

    - a table ``<!-- table data/x.csv | col | col = Header | col = Header : .2f | where k=v,k2=v2 -->``
      followed by the generated table and ``<!-- /table -->``: the rows of ``data/x.csv`` (path
      relative to the Markdown file) that match every ``where`` pair, the listed columns (all
      when none are listed) with an optional header and Python format spec; ``| first N``
      keeps the first N matching rows (a CSV sorted by what matters, e.g. CPU);
    - a number ``<!-- v data/x.csv | col : .2f | where k=v -->23.83<!-- /v -->``: the one
      matching row's cell.

    ``render`` rewrites what lies between the markers from the CSVs; ``check`` renders every
    file in memory and lists each place where the committed text differs — a number in the
    prose that drifted from its CSV, or a CSV regenerated without updating the docs.
    Every CSV under ``docs/data/`` names the command that made it in ``docs/data/README.md``.
    """
    text = TABLE.sub(lambda m: m.group(1) + _table(base, m.group("spec")) + m.group(4), text)
    return VALUE.sub(lambda m: m.group(1) + _value(base, m.group("spec")) + m.group(4), text)


def doc_files(root: Path = ROOT) -> list[Path]:
    """The docs whose tables are rendered: README.md and docs/*.md."""
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]


def check(files: list[Path]) -> list[str]:
    """Unified diffs (one string per file) where the committed text differs from its render."""
    problems = []
    for f in files:
        text = f.read_text()
        new = render(text, f.parent)
        if new != text:
            problems.append("".join(difflib.unified_diff(
                text.splitlines(True), new.splitlines(True), str(f), f"{f} (from its CSVs)")))
    return problems


def main(argv: list[str] | None = None) -> int:
    """``python -m papf.doctools.tables check|render [FILE.md ...]`` (default: README and docs/)."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] not in ("check", "render"):
        print("usage: python -m papf.doctools.tables check|render [FILE.md ...]", file=sys.stderr)
        return 2
    files = [Path(a) for a in args[1:]] or doc_files()
    try:
        if args[0] == "render":
            for f in files:
                f.write_text(render(f.read_text(), f.parent))
            return 0
        problems = check(files)
    except ConfigError as exc:
        print(f"docs: {exc}", file=sys.stderr)
        return 2
    for p in problems:
        print(p)
    if problems:
        print(f"docs-check: {len(problems)} file(s) differ from their CSVs; `make docs` "
              "regenerates them", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
