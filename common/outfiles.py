"""Every file we write goes through here: never over a user's file unless told, never over an input.

An existing output is refused unless ``force``, an output that is an input always, and the
content is written beside and renamed into place (docs/architecture.md "Files we write").
:func:`output` for whole files, :func:`exclusive` for the recorder's file; used by every
command that writes.
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from common.errors import PapfError


class OutputError(PapfError):
    """An output file that would replace a user's file or one of the inputs."""


def same_file(a: str | Path, b: str | Path) -> bool:
    """True when ``a`` and ``b`` are the same file (inode and device), links followed."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def check_output(out: str | Path, inputs: Iterable[str | Path] = (), force: bool = False) -> Path:
    """``out`` as a Path once it may be written (OutputError, one line, otherwise)."""
    out = Path(out)
    for src in inputs:
        if same_file(out, src):
            raise OutputError(f"{out}: is the input {src} (the same file); name another output")
    if not out.parent.is_dir():
        raise OutputError(f"{out}: directory {str(out.parent)!r} does not exist")
    if not os.access(out.parent, os.W_OK | os.X_OK):   # found now, not after the work
        raise OutputError(f"{out}: directory {str(out.parent)!r} is not writable")
    if os.path.lexists(out):
        if out.is_dir() and not out.is_symlink():
            raise OutputError(f"{out}: is a directory; name a file")
        if not force:
            what = "a symlink" if out.is_symlink() else "a file"
            raise OutputError(f"{out}: {what} already exists; use --force to replace it, "
                              "or name another output")
    return out


@contextlib.contextmanager
def output(out: str | Path, inputs: Iterable[str | Path] = (), force: bool = False,
           suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``out``; on success it is renamed onto ``out``.

    ``suffix``: the temporary file's (default ``out``'s, so libraries that pick a format by
    suffix still do). Without ``force`` the rename refuses a file that appeared meanwhile.

    The rule (docs/architecture.md "Files we write"):

    - an existing output is refused unless ``force`` (the CLI's ``--force``);
    - an output that *is* one of the inputs (same inode and device: a hard link, a symlink, a
      ``./`` spelling) is refused even with ``force``;
    - a symlink as output is never followed: with ``force`` the link itself is replaced;
    - the content is written to a temporary file beside the output and renamed onto it at the
      end, so a failure leaves the old file (or nothing), never half a file.

    :func:`output` yields the temporary path (for libraries that take a file name: matplotlib,
    foxglove, imageio); :func:`exclusive` creates a file that must not exist (the recorder, which
    writes in place so that a killed run's recording stays on disk for ``papf recover``).
    """
    inputs = list(inputs)
    out = check_output(out, inputs, force)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{out.name}.", suffix=out.suffix if suffix is None
                                    else suffix, dir=out.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    os.chmod(tmp, 0o666 & ~_umask())   # as open() would have made it (mkstemp: 0600)
    try:
        yield tmp
        _publish(tmp, out, force)
    finally:
        tmp.unlink(missing_ok=True)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _publish(tmp: Path, out: Path, force: bool) -> None:
    """Rename ``tmp`` onto ``out``; without ``force`` only if ``out`` still does not exist."""
    if force:
        os.replace(tmp, out)   # replaces a symlink itself, never its target
        return
    try:
        os.link(tmp, out)      # atomic, and fails if out exists
    except FileExistsError:
        raise OutputError(f"{out}: appeared while writing; nothing replaced "
                          "(use --force, or name another output)") from None
    except OSError as exc:     # a file system without hard links
        if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK):
            raise
        if os.path.lexists(out):
            raise OutputError(f"{out}: appeared while writing; nothing replaced") from None
        os.replace(tmp, out)


def replace_text(out: str | Path, text: str, encoding: str = "utf-8") -> None:
    """``text`` into ``out``, replacing the file an earlier run of the same command made (an
    experiment's own tables in its ``--out`` directory): beside, then renamed; a symlink there
    is replaced, never written through."""
    with output(out, force=True) as tmp:
        tmp.write_text(text, encoding=encoding)


def append_jsonl(out: str | Path):
    """``out`` opened to append JSON lines (a trace, a benchmark's log: append-only by design),
    line-buffered. An existing ``out`` must be a regular file, never a symlink, that is empty
    or starts with a JSON object line: a recording or a user's text is never appended to."""
    import json

    out = Path(out)
    if os.path.lexists(out):
        if out.is_symlink() or not out.is_file():
            raise OutputError(f"{out}: is not a regular file (a symlink, a directory); name a "
                              ".jsonl file of this tool or a new one")
        with out.open("rb") as fh:
            first = fh.readline(1024 * 1024)
        try:
            ok = not first.strip() or isinstance(json.loads(first), dict)
        except ValueError:
            ok = False
        if not ok:
            raise OutputError(f"{out}: exists and is not a file of JSON lines; name a new file")
    else:
        check_output(out)
    flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_NOFOLLOW", 0)
    return os.fdopen(os.open(out, flags, 0o644), "a", encoding="utf-8", buffering=1)


def exclusive(out: str | Path, force: bool = False, mode: str = "wb"):
    """``out`` opened for writing, created new (never through a symlink): OutputError if it
    exists, unless ``force`` (then the old file or link is removed first)."""
    out = check_output(out, (), force)
    if force and os.path.lexists(out):
        out.unlink()
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(out, flags, 0o644)
    except FileExistsError:
        raise OutputError(f"{out}: already exists; use --force to replace it") from None
    return os.fdopen(fd, mode)
