"""The command examples of README.md and docs/*.md, for the tests that run them.

Every line of a shell block is an example; :func:`concrete` makes a synopsis runnable.
Used by ``tests/unit/test_docs_examples.py`` (parsed) and ``tests/e2e/test_docs_examples.py``
(run).
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SESSION_MARK = "<!-- examples: one session -->"   # the blocks after it, to the next heading
HEADING = re.compile(r"^#+ ", re.M)
BLOCK = re.compile(r"^[ \t]*```(?P<lang>[a-z]*)\n(?P<body>.*?)^[ \t]*```", re.S | re.M)
COMMAND_START = re.compile(r"^(papf|python|python3|\.venv/bin/\S+|make|sudo|git|scp|ros2|"
                           r"zenoh-bridge-ros2dds)\b")
# placeholders of the docs -> a value that exists here (the loopback stands in for the robot)
PLACEHOLDERS = {"<robot>": "127.0.0.1", "<robot-ip>": "127.0.0.1", "<this-host>": "127.0.0.1",
                "<node>": "planner", "<repo>": "papf-stack", "<commit>": "HEAD",
                "<this repository>": "papf-stack"}
WORDS = {"W": "energy", "DIR": "out", "F": "out.csv", "F.mcap": "run.mcap", "N": "1", "S": "1",
         "W1,W2": "energy", "S1,S2": "0", "P1,P2": "default", "PORT": "8765", "NAME=VALUE": "v_max=0.2",
         "FILES...": "run.mcap", "DIR|FILES...": "energy-experiment"}


@dataclass(frozen=True)
class Example:
    """One command of the docs: where it is and what it says."""

    file: str          # relative to the repository, e.g. README.md
    line: int          # 1-based line of its first physical line
    text: str          # the command, continuations joined, comment dropped
    block: int         # index of its code block in the file
    background: bool   # ends with ``&``
    session: int = -1  # the block whose session it runs in (-1: its own; see examples())

    @property
    def group(self) -> int:
        """The code block whose session runs this example (:func:`examples`)."""
        return self.block if self.session < 0 else self.session

    @property
    def where(self) -> str:
        """``file:line`` of the example."""
        return f"{self.file}:{self.line}"

    @property
    def program(self) -> str:
        """The command's program (its first word)."""
        return self.text.split()[0]


def doc_files(root: Path = ROOT) -> list[Path]:
    """The docs whose examples are checked: README.md and docs/*.md."""
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]


def _strip_comment(line: str) -> str:
    """``cmd  # note`` -> ``cmd`` (a ``#`` inside quotes is kept)."""
    out, quote = [], None
    for i, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            break
        out.append(ch)
    return "".join(out).rstrip()


def _block_commands(body: str, first_line: int) -> list[tuple[int, str]]:
    """(line, command) of a block's body, continuations joined."""
    out, pending, start = [], "", 0
    for k, raw in enumerate(body.splitlines()):
        line = _strip_comment(raw.strip())
        if not pending:
            start = first_line + k
        if not line:
            continue
        if line.startswith("[") and out and not pending:   # a synopsis's next line
            out[-1] = (out[-1][0], f"{out[-1][1]} {line}")
            continue
        if line.endswith("\\"):
            pending += line[:-1].strip() + " "
            continue
        out.append((start, (pending + line).strip()))
        pending = ""
    return out


def examples(root: Path = ROOT) -> list[Example]:
    r"""Every command example of README.md and docs/*.md, in file order.

    Every line of a ``bash``/``sh`` block, and of an unlabelled block whose lines look like
    commands, is an example: comments dropped, ``\`` continuations joined. A *synopsis*
    (``papf experiment random [--n 50] [--seed S]``) is made concrete by :func:`concrete`:
    optional ``[...]`` groups dropped, ``a|b`` choices and placeholders (``<robot>``, ``W``,
    ``DIR``) replaced by a real value. A *session* is a block with a line ending in ``&``: its
    lines run in order in one shell, the background ones stopped at the end. A step-by-step
    procedure whose blocks belong together (start a scheduler, then workers, then the sweep)
    has :data:`SESSION_MARK` before its first block: the blocks from there to the next
    heading run as one session (their ``session``: the first one's index).

    ``tests/unit/test_docs_examples.py`` parses every ``papf`` example with the real parser and
    checks that every other one is a known module, a Makefile target or an external tool
    named with the reason it cannot run here; ``tests/e2e/test_docs_examples.py`` runs them.
    """
    found = []
    for path in doc_files(root):
        text = path.read_text()
        marks = [m.start() for m in re.finditer(re.escape(SESSION_MARK), text)]
        spans = [(m.start(), m.end()) for m in BLOCK.finditer(text)]
        heads = [h.start() for h in HEADING.finditer(text)   # a "# comment" in a block is none
                 if not any(a <= h.start() < b for a, b in spans)]
        sessions: dict[int, int] = {}   # mark position -> its first block
        for b, m in enumerate(BLOCK.finditer(text)):
            if m.group("lang") not in ("bash", "sh", ""):
                continue
            mark = max((k for k in marks if k < m.start()
                        and not any(k < h < m.start() for h in heads)), default=None)
            session = -1 if mark is None else sessions.setdefault(mark, b)
            first = text.count("\n", 0, m.start("body")) + 1
            cmds = _block_commands(m.group("body"), first)
            if m.group("lang") == "" and not all(COMMAND_START.match(c) for _, c in cmds):
                continue   # a diagram or an output sample, not commands
            for line, cmd in cmds:
                bg = cmd.endswith("&")
                found.append(Example(str(path.relative_to(root)), line,
                                     cmd[:-1].rstrip() if bg else cmd, b, bg, session))
    return found


def _drop_optional(text: str) -> str:
    """Remove ``[...]`` groups (nested ones too)."""
    prev = None
    while prev != text:
        prev, text = text, re.sub(r"\s*\[[^\[\]]*\]", "", text)
    return text


def _word(word: str) -> str:
    for key, value in PLACEHOLDERS.items():
        word = word.replace(key, value)
    if word in WORDS:
        return WORDS[word]
    if "|" in word and not word.startswith(("'", '"')):   # a|b (a choice): the first one
        word = word.split("|")[0]
    return word


def concrete(example: Example) -> list[str]:
    """The example as an argv: optional groups dropped, choices and placeholders filled."""
    return [_word(w) for w in shlex.split(_drop_optional(example.text))]


def papf_argv(example: Example) -> list[str] | None:
    """The arguments after ``papf`` (also ``.venv/bin/papf``), or None for another program."""
    argv = concrete(example)
    return argv[1:] if argv and Path(argv[0]).name == "papf" else None
