"""Text fit for a terminal: what a peer, a file or a user wrote, shown but never run.

A key, a node name, a world name or a log line may carry ESC sequences (clear the screen,
retitle the window, move the cursor) or be megabytes long. Everything we print that came
from outside goes through :func:`safe_text` (one value) or :func:`safe_line` (a whole
message): control and other non-printable characters are shown escaped (``\\x1b``), and
the text is cut at a readable length with the full length said. Used by the CLI's error
lines, the logging of every process (:class:`SafeLogFilter`), ``papf topic`` and the
launcher's echo of its children's lines.
"""

from __future__ import annotations

import logging

MAX_TEXT_CHARS = 200    # [chars] of one value shown (the rest counted)
MAX_LINE_CHARS = 400    # [chars] of one message line shown (an error, a log line)


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


def safe_line(text: str, max_chars: int = MAX_LINE_CHARS) -> str:
    """One message line (an error, a log record) as :func:`safe_text`, cut at ``max_chars``."""
    return safe_text(text, max_chars)


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
