"""CPU seconds per process (and per thread kind) of this process's descendants, from /proc.

:class:`TreeCPU` samples every ``period_s`` in a thread, so a child's last figures are
kept after it exits (Linux only; elsewhere it reports nothing). Used by ``bench sim``.
"""

from __future__ import annotations

import collections
import os
import re
import threading

TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def _stat(path: str):
    try:
        with open(path) as fh:
            s = fh.read()
    except OSError:
        return None
    r = s.rfind(")")
    f = s[r + 2:].split()
    return s[s.find("(") + 1:r], int(f[1]), (int(f[11]) + int(f[12])) / TICK


class TreeCPU:
    def __init__(self, period_s: float = 0.05):
        self.period_s, self.root = period_s, os.getpid()
        self.names: dict[int, str] = {}
        self.threads: dict[tuple[int, int], tuple[str, float]] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="tree-cpu")

    def __enter__(self) -> TreeCPU:
        if os.path.isdir("/proc"):
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        self._sample()

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            self._sample()

    def _sample(self) -> None:
        parents = {}
        for d in os.listdir("/proc"):
            if d.isdigit() and (st := _stat(f"/proc/{d}/stat")):
                parents[int(d)] = st[1]
        tree, grew = {self.root}, True
        while grew:
            new = {p for p, pp in parents.items() if pp in tree and p not in tree}
            tree |= new
            grew = bool(new)
        for pid in tree:
            if pid not in self.names:
                self.names[pid] = _name(pid, self.root)
            try:
                tids = os.listdir(f"/proc/{pid}/task")
            except OSError:
                continue
            for tid in tids:
                if st := _stat(f"/proc/{pid}/task/{tid}/stat"):
                    self.threads[(pid, int(tid))] = (st[0], st[2])

    def per_process(self) -> dict[str, dict]:
        """name -> {"cpu_s": total, "python_s": Python threads, "zenoh_s": Zenoh's threads}."""
        out: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
        for (pid, _tid), (comm, cpu) in self.threads.items():
            name = self.names.get(pid, str(pid))
            kind = "python_s" if comm.startswith(("python", "pt_main")) or pid == self.root and \
                not re.match(r"(rx|tx|net|acc|app)-\d+", comm) else "zenoh_s"
            out[name]["cpu_s"] += cpu
            out[name][kind] += cpu
        return {k: {m: round(v, 2) for m, v in c.items()} for k, c in
                sorted(out.items(), key=lambda kv: -kv[1]["cpu_s"])}


def _name(pid: int, root: int) -> str:
    if pid == root:
        return "launcher"
    try:
        with open(f"/proc/{pid}/cmdline") as fh:
            argv = fh.read().split("\0")
    except OSError:
        return str(pid)
    return argv[argv.index("-m") + 1] if "-m" in argv else os.path.basename(argv[0])
