"""Each finished run of an experiment on disk as it ends, and a re-run that skips them.

:class:`Journal` keeps one JSON file per finished run in ``OUT/runs/`` (named by
:func:`run_key`, written atomically), so Ctrl-C or a crash loses no finished run and the
same command into the same ``OUT`` makes only the others. Used by the experiments.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from common.outfiles import output

MAX_ENTRY_BYTES = 16 * 1024 * 1024   # [bytes] one run's entry (a path of ~10^5 points)


def run_key(*parts: Any) -> str:
    """A digest of a run's defining values (world text, planner, seed, settings, ...)."""
    return hashlib.sha256(json.dumps([str(p) for p in parts]).encode()).hexdigest()[:24]


class Journal:
    """Finished runs under ``out/runs/``.

    Ctrl-C (or a crash) in the middle of an experiment must not throw away the runs already
    made. :class:`Journal` keeps one small JSON file per finished run in ``OUT/runs/``, named
    by a digest of everything that defines the run (:func:`run_key`), written atomically
    (:func:`common.outfiles.output`) the moment the run ends. Running the same experiment into
    the same ``OUT`` again takes those runs from their files (a note says how many) and makes
    only the others; delete ``OUT/runs/`` to make them all again. A file that does not parse,
    or was made for another run, is ignored (that run is made again), never trusted.
    """

    def __init__(self, out: str | Path):
        self.dir = Path(out) / "runs"
        self.taken = 0   # runs resumed from their files

    def _file(self, key: str) -> Path:
        return self.dir / f"{key}.json"

    def get(self, key: str) -> dict | None:
        """The stored entry of run ``key``, or None (not finished, or unreadable)."""
        path = self._file(key)
        try:
            if path.is_symlink() or path.stat().st_size > MAX_ENTRY_BYTES:
                return None
            entry = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if not isinstance(entry, dict) or entry.get("key") != key or not isinstance(entry.get("data"), dict):
            return None
        self.taken += 1
        return entry["data"]

    def put(self, key: str, data: dict) -> None:
        """Store run ``key``'s entry now (replacing an older one of the same run)."""
        self.dir.mkdir(parents=True, exist_ok=True)
        with output(self._file(key), force=True) as tmp:
            tmp.write_text(json.dumps({"key": key, "data": data}), encoding="utf-8")
