"""Where a YAML or TOML text is broken, in one line a user can act on.

PyYAML and tomllib both know the line and column of a syntax error, but say it in their
own ways (PyYAML over several lines, 0-based marks; tomllib "at line L, column C" or "at
end of document"). :func:`yaml_problem` and :func:`toml_problem` give one form for every
file and value we parse — world files, launch profiles, planner settings, ROS map YAMLs,
``papf topic pub`` values:

    line 2, column 13: expected ',' or ']', but got ':' (in "resolution: [0.05 x")

Lines and columns count from 1, as editors show them; the line quoted is cut at
:data:`QUOTE_CHARS` and made terminal-safe.
"""

from __future__ import annotations

import re

from common.text import safe_text

QUOTE_CHARS = 60   # [chars] of the broken line quoted
_TOML_AT = re.compile(r"^(?P<what>.*?)\s*\(at (?:line (?P<line>\d+), column (?P<col>\d+)|"
                      r"(?P<end>end of document))\)\s*$", re.S)


def _quote(text: str, line: int) -> str:
    lines = text.splitlines()
    if not 1 <= line <= len(lines) or not lines[line - 1].strip():
        return ""
    return f" (in {safe_text(lines[line - 1].strip(), QUOTE_CHARS)!r})"


def yaml_problem(exc: Exception, text: str) -> str:
    """``line L, column C: problem (in "the line")`` of PyYAML's error ``exc`` on ``text``
    (its first line alone when it carries no position)."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    context, start = getattr(exc, "context", None), getattr(exc, "context_mark", None)
    one_line = "\n" not in text.rstrip("\n")   # a value (topic pub): columns say it all
    if context and getattr(exc, "problem", None):
        where = ("" if start is None or start is mark else f" at column {start.column + 1}"
                 if one_line else f" at line {start.line + 1}, column {start.column + 1}")
        what = f"{problem} ({context} started{where})" if where else f"{problem} ({context})"
    else:
        what = problem
    if mark is None:
        return safe_text(what)
    line, col = mark.line + 1, mark.column + 1
    if one_line:
        return f"column {col}: {safe_text(what)}"
    return f"line {line}, column {col}: {safe_text(what)}{_quote(text, line)}"


def toml_problem(exc: Exception, text: str) -> str:
    """``line L, column C: problem (in "the line")`` of tomllib's error ``exc`` on ``text``;
    an error "at end of document" (an array or string left open) names the last line."""
    m = _TOML_AT.match(str(exc))
    if m is None:
        return safe_text(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
    what = m.group("what")
    if m.group("end"):
        last = len(text.splitlines()) or 1
        return (f"line {last}, at the end of the file: {safe_text(what)} (a [, {{ or quote "
                f"opened earlier is never closed){_quote(text, last)}")
    line, col = int(m.group("line")), int(m.group("col"))
    return f"line {line}, column {col}: {safe_text(what)}{_quote(text, line)}"
