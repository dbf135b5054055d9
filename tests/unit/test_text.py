"""Terminal-safe text (common/text.py): what a user or a peer typed is shown escaped, never run;
a flood is cut and says how long it was; an error is one whole line when piped and wrapped at
words on a terminal. Property-based where the input space is open."""

from __future__ import annotations

import io
import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.text import MAX_LINE_CHARS, SafeLogFilter, error_text, safe_line, safe_text
from tests.support.cli import papf

SETTINGS = settings(max_examples=60, deadline=None)


@SETTINGS
@given(st.text(max_size=2000), st.booleans())
def test_safe_text_never_passes_a_control_character(text, keep):
    out = safe_text(text, 300, keep_newlines=keep)
    assert all(c.isprintable() or (keep and c == "\n") for c in out)
    assert len(out) <= 300 * 10 + 40   # an escaped character is at most 10 long (\U0010ffff)


def test_an_error_quoting_a_hostile_world_name_is_one_short_safe_line(capsys):
    from papf.cli import main

    name = "\x1b]0;owned\x07\x1b[2J" + "w" * 100_000
    assert main(["plan", "--world", name]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "\x1b" not in err and "\x07" not in err
    assert len(err) < MAX_LINE_CHARS + 100


def test_a_usage_error_quoting_the_user_is_escaped(capsys):
    from papf.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["run", "--planner", "\x1b[31mred" + "p" * 5000])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and len(err) < MAX_LINE_CHARS + 200


def test_log_lines_show_escape_sequences_never_run_them():
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    handler.addFilter(SafeLogFilter())
    log = logging.getLogger("test_text")
    log.addHandler(handler)
    try:
        log.warning("ignored a goal from %s", "\x1b[2Jpeer\r" + "z" * 10_000)
    finally:
        log.removeHandler(handler)
    line = stream.getvalue()
    assert "\x1b" not in line and "\r" not in line and "\\x1b[2Jpeer" in line
    assert len(line) < MAX_LINE_CHARS + 40


def test_safe_line_cuts_a_flood_and_says_how_long():
    assert safe_line("a" * 100_000).endswith("(100,000 chars)")   # a flood is cut
    assert safe_line("a" * 10_000) == "a" * 10_000                  # a message never


def test_a_long_error_line_is_whole_when_piped():
    res = papf("run", "--world", "papf-tst-1")
    assert res.returncode == 2 and "(or pass a path to a .toml file)" in res.stderr
    assert "chars)" not in res.stderr and res.stderr.count("\n") == 1


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_long_error_is_wrapped_at_words_for_a_terminal(monkeypatch):
    monkeypatch.setenv("COLUMNS", "60")
    message = "no packaged world named 'x'; packaged worlds: " + ", ".join(f"w{i}" for i in range(80))
    text = error_text("papf run", message, _Tty())
    lines = text.split("\n")
    assert len(lines) > 3 and all(len(line) <= 60 for line in lines)
    assert " ".join(line.strip() for line in lines) == f"papf run: {message}"
    assert error_text("papf run", message, io.StringIO()) == f"papf run: {message}"
