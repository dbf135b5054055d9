"""Text fit for a terminal: what a peer, a file or a user wrote, shown but never run.

A key, a node name, a world name or a log line may carry ESC sequences (clear the screen,
retitle the window, move the cursor) or be megabytes long. Everything we print that came
from outside goes through :func:`safe_text` (one value) or :func:`safe_line` (a whole
message): control and other non-printable characters are shown escaped (``\\x1b``), and
one value is cut at a readable length with the full length said. A message line (an
error, a log line) is whole: only a line long enough to flood a terminal (a peer's
megabyte key) is cut, with its length said. Used by the CLI's error lines
(:func:`error_text`: whole, wrapped at word boundaries for a terminal, as it is when
piped), the logging of every process (:class:`SafeLogFilter`), ``papf topic`` and the
launcher's echo of its children's lines.
"""

from __future__ import annotations

import difflib
import logging
import shutil
import textwrap
from collections.abc import Iterable

MAX_TEXT_CHARS = 200      # [chars] of one value shown (the rest counted)
MAX_LINE_CHARS = 20_000   # [chars] of one log line shown: a flood is cut, a message never


def safe_text(text: str, max_chars: int | None = MAX_TEXT_CHARS, keep_newlines: bool = False) -> str:
    """``text`` with control and other non-printable characters escaped (a peer's ESC
    sequences are shown, never run), cut at ``max_chars`` (None: whole). ``keep_newlines``:
    a ``\\n`` stays a line break (a traceback), every other control character is escaped."""
    text = str(text)
    cut = text if max_chars is None or len(text) <= max_chars else text[:max_chars]
    if not cut.isprintable():
        cut = "".join(c if c.isprintable() or (keep_newlines and c == "\n")
                      else c.encode("unicode_escape").decode("ascii") for c in cut)
    return cut + (f"… ({len(text):,} chars)" if max_chars is not None and len(text) > max_chars
                  else "")


def suggest(word: str, choices: Iterable[str], n: int = 3, quote: bool = False) -> str:
    """``"; did you mean X?"`` (``X or Y?`` when several are as near) for the choices nearest
    ``word`` (difflib); "" when none is near. ``quote``: the names in quotes."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=n, cutoff=0.6)
    if quote:
        close = [repr(c) for c in close]
    if not close:
        return ""
    return "; did you mean " + (close[0] if len(close) == 1
                                else ", ".join(close[:-1]) + " or " + close[-1]) + "?"


def safe_line(text: str, max_chars: int | None = MAX_LINE_CHARS) -> str:
    """One message line (a log record, a child's output line) as :func:`safe_text`, cut
    only past ``max_chars`` (None: whole)."""
    return safe_text(text, max_chars)


def error_text(prog: str, message: str, stream=None) -> str:
    """``prog: message`` escaped and whole (never cut: the fix hint is at its end); wrapped
    at word boundaries to the terminal's width when ``stream`` is a terminal (continuation
    lines indented), one line when piped — a script or a log gets the whole line as is."""
    line = f"{prog}: {safe_text(message, None)}"
    width = terminal_width(stream)
    if width is None or len(line) <= width:
        return line
    return textwrap.fill(line, width=width, subsequent_indent="  ", break_long_words=False,
                         break_on_hyphens=False)


def terminal_width(stream) -> int | None:
    """The columns of the terminal ``stream`` writes to; None when it is no terminal."""
    try:
        if stream is None or not stream.isatty():
            return None
    except (AttributeError, ValueError):   # a closed or wrapped stream: treat as piped
        return None
    return max(shutil.get_terminal_size((80, 24)).columns, 20)


def print_error(prog: str, message: str, stream=None) -> None:
    """:func:`error_text` on ``stream`` (default stderr)."""
    import sys

    stream = sys.stderr if stream is None else stream
    print(error_text(prog, message, stream), file=stream, flush=True)


class SafeLogFilter(logging.Filter):
    """Every log record's message made terminal-safe (escapes shown, cut at
    :data:`MAX_LINE_CHARS`, line breaks kept); attached to the handlers of every process."""

    def filter(self, record: logging.LogRecord) -> bool:
        try:
            message = record.getMessage()
        except Exception:   # a record whose arguments do not fit its format: logging's own report
            return True
        record.msg, record.args = safe_text(message, MAX_LINE_CHARS, keep_newlines=True), ()
        return True


def install_log_filter() -> None:
    """Attach :class:`SafeLogFilter` to each handler of the root logger (once)."""
    for handler in logging.getLogger().handlers:
        if not any(isinstance(f, SafeLogFilter) for f in handler.filters):
            handler.addFilter(SafeLogFilter())
