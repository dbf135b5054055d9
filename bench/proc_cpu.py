"""CPU seconds per process (and per thread kind) of this process's descendants, from /proc.

:class:`TreeCPU` samples every ``period_s`` in a thread, so a child's last figures are
kept after it exits (Linux only; elsewhere it reports nothing). It walks the tree through
``/proc/PID/task/TID/children`` (a scan of /proc where the kernel lacks it) and leaves its
own sampling thread out of the root's figures. The root's threads are charged only with what
they used inside the ``with`` block (their CPU at entry subtracted): a bench that runs the
stack in its own process several times reports each run's launcher, not the sum so far.
Used by ``bench sim``.
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
        self._own_tid: int | None = None   # the sampler's own thread: not the run's CPU
        self._pre_exec = _name(self.root, -1)  # what a forked child is called until it execs
        self._root_before: dict[int, float] = {}   # the root's threads: CPU at entry [s]
        self._thread = threading.Thread(target=self._run, daemon=True, name="tree-cpu")

    def __enter__(self) -> TreeCPU:
        if os.path.isdir("/proc"):
            for tid in os.listdir(f"/proc/{self.root}/task"):
                if st := _stat(f"/proc/{self.root}/task/{tid}/stat"):
                    self._root_before[int(tid)] = st[2]
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        self._sample()

    def _run(self) -> None:
        self._own_tid = threading.get_native_id()
        while not self._stop.wait(self.period_s):
            self._sample()

    def _sample(self) -> None:
        stack, seen = [(self.root, self._pre_exec)], set()
        while stack:                      # the tree from the root, by each task's children
            pid, parent = stack.pop()
            if pid in seen:
                continue
            seen.add(pid)
            if self.names.get(pid) in (None, "", parent):  # seen between fork and exec: the
                self.names[pid] = _name(pid, self.root)     # parent's name until it execs
            try:
                tids = os.listdir(f"/proc/{pid}/task")
            except OSError:
                continue
            for tid in tids:
                if st := _stat(f"/proc/{pid}/task/{tid}/stat"):
                    self.threads[(pid, int(tid))] = (st[0], st[2])
                stack += [(c, self.names[pid]) for c in _children(pid, tid)]

    def per_process(self) -> dict[str, dict]:
        """name -> {"cpu_s": total, "python_s": Python threads, "zenoh_s": Zenoh's threads}."""
        out: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
        for (pid, tid), (comm, cpu) in self.threads.items():
            if pid == self.root and tid == self._own_tid:
                continue
            if pid == self.root:
                cpu -= self._root_before.get(tid, 0.0)
            name = self.names.get(pid, str(pid))
            kind = "python_s" if comm.startswith(("python", "pt_main")) or pid == self.root and \
                not re.match(r"(rx|tx|net|acc|app)-\d+", comm) else "zenoh_s"
            out[name]["cpu_s"] += cpu
            out[name][kind] += cpu
        return {k: {m: round(v, 2) for m, v in c.items()} for k, c in
                sorted(out.items(), key=lambda kv: -kv[1]["cpu_s"])}


def _children(pid: int, tid: str) -> list[int]:
    """Children of one task (CONFIG_PROC_CHILDREN); else, once per process, from a /proc scan."""
    try:
        with open(f"/proc/{pid}/task/{tid}/children") as fh:
            return [int(c) for c in fh.read().split()]
    except FileNotFoundError:
        if int(tid) != pid:
            return []
        return [int(d) for d in os.listdir("/proc") if d.isdigit()
                and (st := _stat(f"/proc/{d}/stat")) and st[1] == pid]
    except OSError:
        return []


def _name(pid: int, root: int) -> str:
    if pid == root:
        return "launcher"
    try:
        with open(f"/proc/{pid}/cmdline") as fh:
            argv = fh.read().split("\0")
    except OSError:
        return str(pid)
    return argv[argv.index("-m") + 1] if "-m" in argv else os.path.basename(argv[0])
