"""Reproduce the intermittent hang on Ctrl-C of ``papf launch robot`` (issue 31): start it,
wait for ``ready``, send SIGINT, and see whether every process is gone within a bound.

    .venv/bin/python -m bench.ctrlc_loop --runs 200 [--profile robot] [--csv out.csv]

Not a test (200 launches take ~15 minutes): a loop to run by hand before and after a fix.
Each launch gets its own free port and runtime directory. A launcher that has not exited
``--hang-s`` after the SIGINT is a hang: it gets SIGABRT (``PYTHONFAULTHANDLER=1`` prints
every thread's stack, kept in ``--dump-dir``), then SIGKILL. A launcher that exited but left a
process of its launch behind (found by its port on the command line) counts as an orphan.
One CSV line per launch (``run, ready_s, exit_s, code, hang, orphans``) and a summary line.
"""

from __future__ import annotations

import argparse
import csv
import os
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from papf.launch.supervisor import free_port

READY_S = 90.0     # [s wall] for `papf launch` to say ready (a loaded machine)
RANDOM_S = 3.0     # [s wall] --when random: the SIGINT comes within this of the start
EMULATOR_S = 2.0   # [s wall] --emulator: the robot emulator talks this long before the SIGINT


def _pids_with(port: int) -> list[int]:
    """Live processes whose command line ends in ``:<port>`` (this launch's router and nodes)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            argv = (d / "cmdline").read_bytes().split(b"\0")
            state = (d / "stat").read_text().split()[2]
        except OSError:
            continue
        if state != "Z" and any(a.decode(errors="replace").endswith(f":{port}") for a in argv):
            out.append(int(d.name))
    return out


def one(profile: str, hang_s: float, dump_dir: Path, i: int, when: str = "ready",
        rng: random.Random | None = None, emulator: bool = False, sig: int = signal.SIGINT,
        code_dir: str | None = None) -> dict:
    """Launch once, interrupt once (``when``: once ready, or at a random moment of the first
    ``RANDOM_S`` seconds, start-up included); the row of the CSV."""
    port = free_port()
    with tempfile.TemporaryDirectory(prefix="papf-ctrlc-") as runtime:
        env = {**os.environ, "XDG_RUNTIME_DIR": runtime, "PYTHONFAULTHANDLER": "1"}
        if code_dir:   # another checkout's code (--alternate)
            env["PYTHONPATH"] = code_dir
        cmd = [sys.executable, "-m", "papf", "launch", profile, "--listen", f"tcp/127.0.0.1:{port}"]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                env=env, start_new_session=True)
        lines: list[str] = []
        ready = threading.Event()

        def pump() -> None:
            for line in proc.stderr:   # type: ignore[union-attr]
                lines.append(line)
                if "ready (" in line:
                    ready.set()

        t = threading.Thread(target=pump, daemon=True)
        t.start()
        t0 = time.monotonic()
        row = {"run": i, "sig_s": None, "ignored_at_send": None, "ready_s": None,
               "exit_s": None, "code": None, "hang": 0, "orphans": 0, "code_dir": code_dir or "."}
        if when == "random":
            ready.wait((rng or random).uniform(0.0, RANDOM_S))
        elif not ready.wait(READY_S):
            proc.kill()
            os.killpg(proc.pid, signal.SIGKILL)
            row["code"] = "not-ready"
            return row
        row["ready_s"] = round(time.monotonic() - t0, 3) if ready.is_set() else None
        emu = None
        if emulator and ready.is_set():   # the robot talking: the driver busy, samples flowing
            emu = subprocess.Popen([sys.executable, "-m", "papf", "rosbot-emulator", "--connect",
                                    f"tcp/127.0.0.1:{port}"], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL, env=env, start_new_session=True)
            time.sleep(EMULATOR_S)
        row["ignored_at_send"] = int(_ignores(proc.pid, sig))
        t1 = time.monotonic()
        row["sig_s"] = round(t1 - t0, 3)
        proc.send_signal(sig)
        try:
            row["code"] = proc.wait(timeout=hang_s)
            row["exit_s"] = round(time.monotonic() - t1, 3)
        except subprocess.TimeoutExpired:
            row["hang"] = 1
            proc.send_signal(signal.SIGABRT)   # faulthandler: every thread's stack on stderr
            time.sleep(1.0)
            with open(dump_dir / f"hang-{i}.txt", "w") as f:
                f.writelines(lines)
            proc.kill()
            proc.wait()
        t.join(2.0)
        if emu is not None:
            os.killpg(emu.pid, signal.SIGKILL)
            emu.wait()
        row["orphans"] = _reap(port)
        return row


def _ignores(pid: int, sig: int) -> bool:
    """Whether process ``pid`` ignores ``sig`` right now (``SigIgn`` of /proc/PID/status): a
    signal sent then is discarded by the kernel."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("SigIgn:"):
                return bool(int(line.split()[1], 16) >> (sig - 1) & 1)
    except OSError:
        pass
    return False


def _reap(port: int) -> int:
    """How many processes of the launch on ``port`` are still alive 10 s on (killed then):
    a node asked to stop exits within its bound (common.transport: 5 s, SIGALRM at 7 s)."""
    deadline = time.monotonic() + 10.0
    while _pids_with(port) and time.monotonic() < deadline:
        time.sleep(0.1)
    orphans = _pids_with(port)
    for pid in orphans:
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
            print(f"left behind: {pid} {cmd}", file=sys.stderr, flush=True)
        except OSError:
            pass
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return len(orphans)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.ctrlc_loop", description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--profile", default="robot")
    ap.add_argument("--hang-s", type=float, default=20.0, help="a launcher still alive this long "
                    "after SIGINT is a hang (default 20)")
    ap.add_argument("--when", choices=("ready", "random"), default="ready",
                    help="SIGINT once ready (default), or at a random moment of the first "
                         f"{RANDOM_S:g} s (start-up included; seeded)")
    ap.add_argument("--emulator", action="store_true",
                    help="once ready, start papf rosbot-emulator against the launch first (the "
                         "driver busy with odometry, battery and commands), as on a robot")
    ap.add_argument("--signal", choices=("INT", "TERM"), default="INT",
                    help="the signal sent (default INT, what Ctrl-C sends)")
    ap.add_argument("--alternate", metavar="DIR",
                    help="every other launch runs the code in DIR (PYTHONPATH; e.g. a `git "
                         "archive` of the commit before a fix): both under the same load")
    ap.add_argument("--csv", default="-", help="rows here (default stdout)")
    ap.add_argument("--dump-dir", default=".", help="where the stacks of hung launchers go")
    args = ap.parse_args(argv)
    dump = Path(args.dump_dir)
    dump.mkdir(parents=True, exist_ok=True)
    out = sys.stdout if args.csv == "-" else open(args.csv, "w", newline="")  # noqa: SIM115
    writer = csv.DictWriter(out, ["run", "sig_s", "ignored_at_send", "ready_s", "exit_s",
                                  "code", "hang", "orphans", "code_dir"])
    writer.writeheader()
    hangs = orphans = slow = deaf = 0
    by_dir: dict[str, list[int]] = {}
    rng = random.Random(31)
    for i in range(args.runs):
        code_dir = args.alternate if args.alternate and i % 2 else None
        row = one(args.profile, args.hang_s, dump, i, args.when, rng, args.emulator,
                  getattr(signal, "SIG" + args.signal), code_dir)
        writer.writerow(row)
        out.flush()
        hangs += row["hang"]
        deaf += 1 if row["hang"] and row["ignored_at_send"] else 0
        by_dir.setdefault(row["code_dir"], [0, 0])
        by_dir[row["code_dir"]][0] += 1
        by_dir[row["code_dir"]][1] += row["hang"]
        orphans += 1 if row["orphans"] else 0
        slow += 1 if row["exit_s"] is not None and row["exit_s"] > 5.0 else 0
        print(f"run {i + 1}/{args.runs}: hangs {hangs}, launches leaving orphans {orphans}, "
              f"exits over 5 s {slow}", file=sys.stderr, flush=True)
    print(f"of the {hangs} hung, {deaf} ignored the signal when it was sent (inherited SIG_IGN, "
          "before the process took it: the kernel discarded it)", file=sys.stderr)
    for d, (n, h) in by_dir.items():
        print(f"code in {d}: {h} of {n} launches hung", file=sys.stderr)
    print(f"{args.runs} launches of {args.profile}: {hangs} hung (> {args.hang_s:g} s after SIG{args.signal}, "
          f"{orphans} left processes behind, {slow} took over 5 s", file=sys.stderr)
    return 1 if hangs or orphans else 0


if __name__ == "__main__":
    raise SystemExit(main())
