"""A run's secret: the goal and the planner's status are signed, so each side acts only on
messages of the run that set them up.

The launcher makes a fresh key (:func:`new_key`) and hands it to its processes through the
environment (:data:`ENV`, never the bus or a command line); goals, statuses and live
parameter changes carry an HMAC tag (:func:`sign`, :func:`sign_request`). Used by the
launcher, the planner node, ``papf goal`` and ``papf param``.
"""

from __future__ import annotations

import collections
import dataclasses
import hashlib
import hmac
import json
import os
import re
import secrets
import stat
import tempfile
from pathlib import Path

import msgpack

from common import seal
from common.errors import ConfigError, PapfError

ENV = "PAPF_RUN_KEY"          # environment variable that carries the key (hex)
TAG_HEX = 32                  # [hex digits] 128-bit tag
_HEX_TAG = re.compile(f"[0-9a-f]{{{TAG_HEX}}}")   # what a tag looks like (compare_digest: ASCII)


def new_key() -> str:
    """A fresh run key, hex."""
    return secrets.token_hex(16)


def key_from_env(environ=os.environ) -> bytes | None:
    """The run key this process was given, or None."""
    text = environ.get(ENV, "")
    try:
        return bytes.fromhex(text) if text else None
    except ValueError:
        return None


def key_file(namespace: str) -> Path:
    """Where the launcher of ``namespace`` leaves its run key for this user's tools."""
    base = Path(os.environ.get("XDG_RUNTIME_DIR") or tempfile.gettempdir())
    return base / f"papf-{os.getuid()}" / f"{re.sub(r'[^A-Za-z0-9_.-]', '_', namespace)}.key"


class NamespaceTaken(ConfigError):
    """Another launcher of this user holds the namespace (its key file names a live process):
    a user's mistake like any other (exit 2, one line that says what to do)."""


def publish_key(namespace: str, key_hex: str, run_id: str = "") -> Path:
    """Write the run key (and this process id) for this user's ``papf goal``.

    NamespaceTaken when a live launcher already holds ``namespace``: two launches in one
    namespace would share every key of the bus, and the second would take the first's key
    file (the first could no longer be steered).

    An operator on the same host re-targets a running session with ``papf goal X Y``: the
    launcher leaves the key in a file only its user can read (mode 600 in a mode-700
    directory), ``papf goal`` signs with it, and the launcher then judges the run against that
    goal. Another user, host or stack has no key and stays ignored.
    """
    path = key_file(namespace)
    path.parent.mkdir(mode=0o700, exist_ok=True)
    _check_own_dir(path.parent)
    os.chmod(path.parent, 0o700)
    holder = _holder(path)
    if holder is not None and holder != os.getpid():
        raise NamespaceTaken(f"namespace {namespace!r} is in use by another launch of yours "
                             f"(process {holder}); stop it, or give another --namespace")
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0), 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(f"{key_hex} {os.getpid()} {run_id or '-'}\n")
    return path


class KeyDirError(PapfError):
    """The key directory is not this user's own (another user made it, or it is a link)."""


def _check_own_dir(d: Path) -> None:
    """KeyDirError unless ``d`` is a real directory (not a symlink) owned by this user: in a
    shared temporary directory another user could have made ``papf-<uid>`` first."""
    st = os.lstat(d)
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid():
        raise KeyDirError(f"{d}: not a directory of your own (made by another user, or a link); "
                          "remove it, or set XDG_RUNTIME_DIR")


def _holder(path: Path) -> int | None:
    """The live process id in the key file at ``path``, or None (no file, or its launcher died)."""
    try:
        parts = path.read_text().split()
        pid = int(parts[1]) if len(parts) > 1 else None
    except (OSError, ValueError):
        return None
    if pid is None:
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except PermissionError:
        return pid
    return pid


def read_key(namespace: str) -> bytes | None:
    """The run key a launcher of ``namespace`` left for this user, or None (also when the key
    directory is not this user's own: a key another user left is no key)."""
    path = key_file(namespace)
    try:
        _check_own_dir(path.parent)
        return bytes.fromhex(path.read_text().split()[0])
    except (OSError, ValueError, IndexError, KeyDirError):
        return None


def read_run(namespace: str) -> bytes | None:
    """The run id a launcher of ``namespace`` left beside its key (tools seal with it so the
    run's nodes take what they put: ``papf goal``), or None (no run: a serving launch)."""
    path = key_file(namespace)
    try:
        _check_own_dir(path.parent)
        parts = path.read_text().split()
        return bytes.fromhex(parts[2]) if len(parts) > 2 and parts[2] != "-" else None
    except (OSError, ValueError, KeyDirError):
        return None


def sealed_put(session, key_expr: str, payload: bytes, key: bytes | None,
               run: bytes | None = None) -> None:
    """``session.put`` with the seal of ``key`` and ``run`` (common.seal); plain without a key."""
    if key is None:
        session.put(key_expr, payload)
        return
    from common.seal import Sealer  # imported here: seal imports nothing of ours, no cycle

    session.put(key_expr, payload, attachment=Sealer(key, run).seal(key_expr, payload))


# -- a key made once for a split (robot and laptop launched separately) ------------------------
KEY_FILE_BYTES = 32   # [bytes] a pairing key: 256 bits


def pair_file(namespace: str) -> Path:
    """The pairing key both sides of a split on one host use when given no ``--key``."""
    return key_file(namespace).with_suffix(".pair")


def load_pair_key(path: str | Path, create: bool = False) -> tuple[bytes, bool]:
    """The key in ``path`` (hex; made there, mode 600, when missing and ``create``) and
    whether it was made now. PapfError (one line) for a file that is no key, or is readable
    by others (a secret anyone on the host could read steers the robot)."""
    path = Path(path)
    if create and not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL |
                         getattr(os, "O_NOFOLLOW", 0), 0o600)
        except FileExistsError:
            return load_pair_key(path)
        with os.fdopen(fd, "w") as f:
            f.write(secrets.token_hex(KEY_FILE_BYTES) + "\n")
        return load_pair_key(path)[0], True
    try:
        st = os.stat(path)
        text = path.read_text().split()
    except OSError as exc:
        raise PapfError(f"--key {path}: {exc.strerror or exc} (make one with papf launch robot "
                        "--key FILE, then copy FILE to the laptop)") from None
    if st.st_mode & 0o077:
        raise PapfError(f"--key {path}: readable by other users (mode {st.st_mode & 0o777:o}); "
                        f"chmod 600 {path}")
    try:
        key = bytes.fromhex(text[0]) if text else b""
    except ValueError:
        key = b""
    if len(key) < 16:
        raise PapfError(f"--key {path}: not a key file (expected at least 32 hex digits on its "
                        "first line; papf launch robot --key FILE makes one)")
    return key, False


def withdraw_key(namespace: str, key_hex: str) -> None:
    """Remove the key file if it still holds this run's key."""
    path = key_file(namespace)
    try:
        if path.read_text().split()[:1] == [key_hex]:
            path.unlink()
    except OSError:
        pass


def _tag(msg, key: bytes) -> str:
    wire = {k: v for k, v in msg.to_wire().items() if k != "auth"}
    body = msgpack.packb(wire, use_bin_type=True)
    return hmac.new(key, body, hashlib.sha256).hexdigest()[:TAG_HEX]


def sign(msg, key: bytes | None):
    """``msg`` with its ``auth`` tag set (unchanged without a key).

    The launcher signs the goal; the planner accepts only goals that verify, and signs its
    status messages; the launcher accepts only statuses that verify. A goal put on the bus by
    anyone else (another stack, a replay, a hostile peer) is dropped and counted, and so is a
    forged ``reached``. A planner started without a key (alone, for tests) accepts any goal.

    The tag is HMAC-SHA256 (RFC 2104) over the message's msgpack form without its ``auth``
    field, truncated to 128 bits.
    """
    return msg if key is None else dataclasses.replace(msg, auth=_tag(msg, key))


def verify(msg, key: bytes | None) -> bool:
    """True when ``msg`` carries the tag of ``key`` (always True without a key)."""
    if key is None:
        return True
    auth = getattr(msg, "auth", "")
    return isinstance(auth, str) and bool(_HEX_TAG.fullmatch(auth)) and \
        hmac.compare_digest(auth, _tag(msg, key))


# -- live parameter changes: the same key signs a query's JSON request --------------------------
NONCES_KEPT = 4096   # [-] request nonces a node remembers (a replayed request is refused)


def _request_tag(request: dict, key: bytes) -> str:
    body = json.dumps({k: v for k, v in request.items() if k != "auth"}, sort_keys=True,
                      separators=(",", ":")).encode()
    return hmac.new(key, body, hashlib.sha256).hexdigest()[:TAG_HEX]


_FROM_ENV = object()   # sign_request's default run: this process's (its launcher gave it)


def sign_request(request: dict, key: bytes | None, run=_FROM_ENV) -> dict:
    """A parameter request (JSON object) with a fresh ``nonce``, the run it is for (``run``:
    bytes, None for none; default: this process's run, :data:`common.seal.RUN_ID_ENV`) and
    its ``auth`` tag (unchanged without a key). The run id keeps a request captured in one run
    from counting in the next, when both share a key (a split's pairing key)."""
    if key is None:
        return dict(request)
    if run is _FROM_ENV:
        run = seal.run_from_env()
    out = {**request, "nonce": secrets.token_hex(8), **({"run": run.hex()} if run else {})}
    return {**out, "auth": _request_tag(out, key)}


class RequestCheck:
    """A node's check of signed requests: the tag of its run key, each nonce once.

    A live parameter change (the query ``<ns>/planner/params``: ``papf param set``, the
    viewer's Parameters panel) is signed like a goal (:func:`sign_request`): a planner with a
    key lists its settings to anyone but changes them only for a request with this run's tag
    and a nonce it has not seen.
    """

    def __init__(self, key: bytes | None, run: bytes | None = None):
        self.key, self.run = key, run   # run: a request must name this run (sign_request)
        self._seen: collections.OrderedDict[str, None] = collections.OrderedDict()

    def ok(self, request: dict) -> bool:
        """True when ``request`` may change the node (always True without a key)."""
        if self.key is None:
            return True
        auth, nonce = request.get("auth"), request.get("nonce")
        if not (isinstance(auth, str) and _HEX_TAG.fullmatch(auth) and isinstance(nonce, str)
                and len(nonce) <= 64):
            return False
        if not hmac.compare_digest(auth, _request_tag(request, self.key)) or nonce in self._seen:
            return False
        if self.run is not None and request.get("run") != self.run.hex():
            return False   # signed for another run (a capture put again later)
        self._seen[nonce] = None
        while len(self._seen) > NONCES_KEPT:
            self._seen.popitem(last=False)
        return True
