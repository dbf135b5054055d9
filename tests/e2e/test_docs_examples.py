"""Every command example of README.md and docs/*.md runs (papf/doctools/examples.py).

Each code block runs as one session in a fresh directory, its lines in order, against a
router on a free loopback port (``7447`` in a line becomes that port; a command that would
use the default router gets ``--connect``/``--listen``/``--port`` for it). A block with a
``<robot>`` placeholder has ``papf rosbot-emulator`` standing in for the robot. Per command:

- a *server* (a line ending in ``&``, ``papf launch robot``, a node started alone, a
  recorder until Ctrl-C, …) is started in the background and must still be running at the
  end of its block, then stop on SIGINT without a traceback;
- a *short* command runs in a smaller variant (:data:`SHORT`: fewer runs, a sim-time
  limit) and must exit with one of its accepted codes;
- a command that cannot run here (:data:`HELP`: it needs the robot, a second host, a
  terminal, or it takes many minutes) runs with ``--help``; the reason is in the table;
- any other papf command runs as written and must exit 0.

Programs other than papf (``ros2``, ``zenoh-bridge-ros2dds``, ``git``, …) are not run: the
unit test ``tests/unit/test_docs_examples.py`` checks each is one of the known tools.
"""

from __future__ import annotations

import functools
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from papf.doctools.examples import ROOT, Example, concrete, examples
from papf.launch.supervisor import free_port, wait_port
from tests.support import warm
from tests.support.cli import interrupt, papf

pytestmark = pytest.mark.e2e

PY = sys.executable
FAST = ["--set", "v_max=0.5"]
# first words of a papf command -> (extra arguments of its short variant, accepted exit codes)
SHORT: dict[tuple[str, ...], tuple[list[str], set[int]]] = {
    ("run",): (["--timeout", "8"], {0, 3, 5}),
    ("launch", "laptop"): (["--timeout", "8", *FAST], {0, 3, 5}),
    ("launch", "hil-laptop"): (["--timeout", "8", *FAST], {0, 3, 5}),
    ("launch", "sim"): (["--timeout", "8"], {0, 3, 5}),
    ("experiment", "energy"): (["--runs", "1", "--timeout", "4"], {0, 6}),
    ("experiment", "paper-tests"): (["--offline", "--worlds", "papf-test-4", "--planners", "apf",
                                     "--timeout", "30"], {0}),
    ("experiment", "random"): (["--n", "1", "--planners", "apf", "--timeout", "30"], {0}),
    ("experiment", "iapf"): (["--cases", "a", "--planners", "iapf", "--no-horizon"], {0}),
    ("experiment", "traffic"): (["--worlds", "road-stopped", "--planners", "apf",
                                 "--timeout", "5"], {0}),
    # 12 s of sim time: no robot crosses the hall, and every file is still written (a
    # sweep's rows and files: tests/unit/test_crowd_experiment.py)
    ("experiment", "crowd"): (["--planners", "apf", "--people", "0,2", "--runs", "1",
                               "--timeout", "12"], {0}),
    ("replay",): (["--rate", "0"], {0}),
    # followed for 4 s of wall time, not to the goal (5: no outcome yet); the planner's
    # acknowledgement is still required (Session.run)
    ("goal",): (["--timeout", "4"], {0, 5}),
    ("plan",): ([], {0, 3, 4, 5}),     # its exit code is the run's outcome (docs: the papers'
                                       # collisions and stagnations are examples too)
    ("make-certs",): (["--force"], {0}),
    ("report",): (["--force"], {0}),   # a block's report after its experiment wrote one
    # fewer, smaller frames (6.8 s of CPU each at the defaults; tests/e2e/test_progress_piped.py
    # draws an animation at the default size frame by frame)
    ("animate",): (["--speed", "16", "--dpi", "50"], {0}),
}
# a run over an emulated link, a --realtime run and a laptop side driving a robot go at the
# wall clock's pace (the link's delays are real): 3 s of it start the proxy or the robot's run,
# drive and end as a run does (tests/e2e/test_link_*.py, test_launch_profiles.py and
# test_ros_face.py drive whole ones)
WALL_CLOCK_TIMEOUT = ["--timeout", "3"]
WALL_CLOCK = (("launch", "laptop"), ("launch", "hil-laptop"))
WHY_MINUTES = "takes minutes (tests/e2e/test_progress_piped.py runs its first steps)"
HELP: dict[tuple[str, ...], str] = {
    ("teleop",): "reads the keyboard (tests/e2e/test_teleop_robot.py drives it in a pty)",
    ("bench",): "a benchmark, measured quietly by hand (docs/performance.md)",
    ("experiment", "wang"): WHY_MINUTES,
    ("experiment", "horizon"): WHY_MINUTES,
    ("experiment", "deviations"): WHY_MINUTES,
    ("experiment", "test1-sweep"): WHY_MINUTES,
    ("experiment", "cases"): "takes an hour (docs/data/README.md)",
    ("experiment", "link"): "real-time runs for an hour (tests/e2e/test_link_split.py runs one)",
}
HELP_IF = (("/opt/papf/certs", "needs the robot's certificates under /opt/papf"),
           ("laptop.json5", "connects by TLS to the robot's address in the certificate"),
           ("--view", "the viewer is served until Ctrl-C: tests/e2e/test_viewer_protocol.py"))
SERVERS = (("launch", "robot"), ("launch", "hil-robot"), ("rosbot-emulator",), ("view",),
           ("record",))
MAKE_DRY = {"demo", "test", "setup"}      # `make -n`: the recipe exists and expands
SETTLE_S = 2.0   # [s] a server's nodes come up after its first log line (Session.start)


def _match(argv: list[str], table) -> tuple | None:
    for key in sorted(table, key=len, reverse=True):
        if tuple(argv[:len(key)]) == key:
            return key
    return None


def _without_timeout(args: list[str]) -> list[str]:
    """``args`` without a ``--timeout VALUE`` pair."""
    if "--timeout" not in args:
        return args
    k = args.index("--timeout")
    return [*args[:k], *args[k + 2:]]


def _own_view_port(args: list[str]) -> list[str]:
    """A Foxglove view on a free port of its own, never the default 8765: two views of one
    block, or of two blocks on parallel test workers, would take the same port."""
    args = [str(free_port()) if a == "8765" else a for a in args]
    if "--view" in args:
        k = args.index("--view")
        if k + 1 == len(args) or not args[k + 1].isdigit():
            args = [*args[:k + 1], str(free_port()), *args[k + 1:]]
    if args[:1] == ["view"] and "--port" not in args:
        args = [*args, "--port", str(free_port())]
    return args


class Session:
    """A block's commands, in one directory, against one router port."""

    def __init__(self, cwd: Path, port: int):
        self.cwd, self.port = cwd, port
        self.endpoint = f"tcp/127.0.0.1:{port}"
        self.background: list[tuple[str, subprocess.Popen]] = []
        self.log: list[str] = []
        self.needs_robot = False      # start the emulator once a router listens
        self.dask_port = free_port()  # docs/sweeps.md's scheduler (8786 in the docs)
        self.settle_until = 0.0       # [s, monotonic] the last server's nodes are up by then
        self.link_port = free_port()  # docs/link.md's emulator (7448 in the docs)

    def argv(self, ex: Example) -> list[str] | None:
        """The command to run for ``ex`` (None: not a program this test runs)."""
        # in one pass: a free port put in for one of them may hold the digits of another
        ports = {"7447": self.port, "8786": self.dask_port, "7448": self.link_port}
        text = re.sub("7447|8786|7448", lambda m: str(ports[m.group()]), ex.text)
        text = text.replace("10.0.0.5", "127.0.0.1")   # the sweep's scheduler host: this one
        argv = concrete(Example(ex.file, ex.line, text, ex.block, ex.background))
        name = Path(argv[0]).name
        if name == "dask":                             # a scheduler or a worker: a server
            return [str(Path(PY).parent / "dask"), *argv[1:]]
        if name == "papf":
            return [PY, "-m", "papf", *self._papf(argv[1:], ex.background)]
        if name in ("python", "python3") and argv[1:2] == ["-m"] and argv[2] == "pytest":
            return None   # the test commands: the suite does not run itself
        if name in ("python", "python3") and argv[1:2] == ["-m"] and argv[2] != "venv":
            return [PY, *argv[1:], *self._zenoh(argv[2:])]
        if name == "make" and argv[1] in MAKE_DRY:
            return ["make", "-n", "-C", str(ROOT), argv[1]]
        return None

    def _zenoh(self, rest: list[str]) -> list[str]:
        if "--help" in rest or any(a.startswith(("--connect", "--listen")) for a in rest):
            return []
        if rest[0] == "papf.launch.router":
            return ["--listen", self.endpoint]
        return ["--connect", self.endpoint]

    def _papf(self, args: list[str], background: bool) -> list[str]:
        for needle, _why in HELP_IF:
            if needle in " ".join(args):
                return [*args[:_subcommand_len(args)], "--help"]
        if _match(args, HELP):
            return [*args[:_subcommand_len(args)], "--help"]
        short = _match(args, SHORT)
        extra = SHORT[short][0] if short and not background else []
        if not background and (short in WALL_CLOCK or short == ("run",) and (
                "--link" in args or "--realtime" in args)):
            extra = [*WALL_CLOCK_TIMEOUT, *_without_timeout(extra)]   # its other ones kept
        if "--help" in args or "--dry-run" in args:
            return args
        args = _own_view_port(args)
        # a run in the foreground has a router of its own; one in the background is the block's
        port = self.port if background else free_port()
        if args[0] == "run" and "--port" not in args:
            extra = [*extra, "--port", str(port)]
        elif args[0] == "launch" and args[1] in ("robot", "hil-robot", "sim") and \
                "--listen" not in args:
            extra = [*extra, "--listen", f"tcp/127.0.0.1:{port}" if args[1] == "sim"
                     else self.endpoint]
        elif args[0] in ("topic", "node", "param", "goal", "record", "replay",
                         "rosbot-emulator", "launch", "view") and \
                "--connect" not in args and "--zenoh-config" not in args:
            extra = [*extra, "--connect", self.endpoint]
        return [*args, *extra]

    def run(self, ex: Example) -> None:
        argv = self.argv(ex)
        if argv is None:
            return
        papf_args = argv[3:] if argv[1:3] == ["-m", "papf"] else []
        if ex.background or Path(argv[0]).name == "dask" or (
                _match(papf_args, SERVERS) and "--layout" not in argv) or (
                argv[1:2] == ["-m"] and
                                                           argv[2].startswith(("nodes.", "papf.launch.router"))
                                                           and "--help" not in argv):
            self.start(ex, argv)
            return
        short = _match(papf_args, SHORT)
        ok = SHORT[short][1] if short and "--help" not in argv else {0}
        self.settle()
        proc = warm.run(argv, cwd=self.cwd, timeout=600)
        self.log.append(f"$ {' '.join(argv[2:])}  -> {proc.returncode}")
        assert proc.returncode in ok, (f"{ex.where}: {ex.text}\n-> {' '.join(argv)} exited "
                                       f"{proc.returncode}\n{proc.stderr[-3000:]}")
        assert "Traceback" not in proc.stderr, f"{ex.where}: {proc.stderr[-3000:]}"
        if short == ("goal",) and "--help" not in argv:
            assert "acknowledged by the planner" in proc.stdout, f"{ex.where}: {proc.stdout}"

    def start(self, ex: Example, argv: list[str]) -> None:
        with (self.cwd / f"bg-{len(self.background)}.log").open("w") as log:
            proc = warm.popen(argv, cwd=self.cwd, stdout=subprocess.DEVNULL, stderr=log)
        self.background.append((ex.where, proc))
        self.log.append(f"$ {' '.join(argv[2:])} &")
        if argv[2:3] == ["papf.launch.router"] or argv[3:5] == ["launch", "robot"] or \
                argv[3:4] == ["run"]:
            assert wait_port(self.port, 60.0), f"{ex.where}: nothing listens on {self.endpoint}"
            if self.needs_robot and "rosbot-emulator" not in " ".join(argv):
                self.needs_robot = False
                self.start(Example(ex.file, 0, "papf rosbot-emulator", -1, True),
                           [PY, "-m", "papf", "rosbot-emulator", "--connect", self.endpoint])
        if argv[1:2] == ["scheduler"]:
            assert wait_port(self.dask_port, 60.0), f"{ex.where}: no Dask scheduler came up"
        log = self.cwd / f"bg-{len(self.background) - 1}.log"
        deadline = time.monotonic() + 30.0   # its first log line: imported and started
        while not log.read_text().strip() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        # the server's nodes come up: 2 s before the next foreground line or the block's end
        # (the next line finds them alive), not after each server of a row of them
        self.settle_until = time.monotonic() + SETTLE_S

    def settle(self) -> None:
        """Wait out what is left of the last server's :data:`SETTLE_S`."""
        time.sleep(max(0.0, self.settle_until - time.monotonic()))

    def stop(self) -> None:
        """Stop the background processes (last first): each still running, no traceback."""
        self.settle()
        errors = []
        for k, (where, proc) in reversed(list(enumerate(self.background))):
            if proc.poll() is not None and proc.returncode != 0:
                errors.append(f"{where}: exited {proc.returncode} before the end of its block")
            if proc.poll() is None and not interrupt(proc, 40):
                errors.append(f"{where}: did not stop on SIGINT")
            err = (self.cwd / f"bg-{k}.log").read_text()
            # Dask's own nanny may log a CommClosedError traceback while a worker and its
            # scheduler shut down together (seen once in 2 runs): not ours to judge
            if "Traceback" in err and Path(proc.args[0]).name != "dask":
                errors.append(f"{where}: traceback on stop\n{err[-2000:]}")
        assert not errors, "\n".join(errors)


def _subcommand_len(args: list[str]) -> int:
    """How many leading words name the command (``experiment wang``: 2; ``run``: 1)."""
    if args[0] in ("experiment", "topic", "export", "bench", "launch", "node", "param", "new"):
        return 2
    return 1


def _blocks() -> dict[str, list[Example]]:
    """The examples by session: a code block, or the blocks a doc marks as one session."""
    blocks: dict[str, list[Example]] = {}
    for ex in examples():
        blocks.setdefault(f"{ex.file}#{ex.group}", []).append(ex)
    return blocks


BLOCKS = _blocks()


@functools.cache
def _recording() -> bytes:
    """A recording of a short run (open world, APF, 6 s): recorded by the first block of
    this worker that needs one, copied for the others (each block takes it as given)."""
    with tempfile.TemporaryDirectory() as tmp:
        papf("run", "--world", "open", "--planner", "apf", "--record", "run.mcap", "--port",
             str(free_port()), "--timeout", "6", cwd=tmp, timeout=300)
        assert (Path(tmp) / "run.mcap").exists(), "the blocks' recording was not made"
        return (Path(tmp) / "run.mcap").read_bytes()


def _prepare(cwd: Path, block: list[Example]) -> None:
    """What the block's examples take as given: a recording, a broken one, a result dir."""
    text = " ".join(e.text for e in block)
    (cwd / "docs").mkdir(exist_ok=True)    # paths of the docs are relative to the repository
    records_run = any("--record run.mcap" in e.text for e in block)
    needs_run = any(w in text for w in ("run.mcap", "first.mcap")) and not records_run
    # a block that records run.mcap itself gets its other inputs from a recording of its own
    # (recordings are never overwritten: the block's run would refuse an existing run.mcap)
    prep = cwd / ("prep.mcap" if records_run else "run.mcap")
    if needs_run or "broken.mcap" in text or "energy-exp" in text:
        prep.write_bytes(_recording())
    if "broken.mcap" in text:
        data = prep.read_bytes()
        (cwd / "broken.mcap").write_bytes(data[: len(data) * 2 // 3])
    if "first.mcap" in text and "--record first.mcap" not in text:
        shutil.copy(prep, cwd / "first.mcap")
    if "lab-run" in text:   # a rosbag2 as the ROSbot records it (`ros2 bag record` cannot run here)
        from tests.support.bags import write_bag

        write_bag(cwd / "lab-run")
    if "other-bag" in text:   # a robot whose topics have other names (the --topics example)
        from tests.support.bags import write_bag

        write_bag(cwd / "other-bag", names={"odom": "/odom", "battery": "/battery_state"})


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
@pytest.mark.parametrize("block", sorted(BLOCKS))
def test_docs_block_runs(block, tmp_path):
    examples_ = BLOCKS[block]
    session = Session(tmp_path, free_port())
    runnable = [e for e in examples_ if session.argv(e) is not None]
    if not runnable:
        pytest.skip("no command of this block runs here (the unit test checks each program)")
    _prepare(tmp_path, examples_)
    uses_router = any(session.argv(e)[1:3] == ["-m", "papf"] and
                      session.argv(e)[3] in ("topic", "node", "param", "goal", "record", "replay")
                      for e in runnable)
    starts_router = any("papf.launch.router" in e.text or e.text.startswith("papf launch robot")
                        or (e.background and e.text.startswith("papf run")) for e in runnable)
    session.needs_robot = re.search(r"<robot(-ip)?>", " ".join(e.text for e in examples_)) and \
        not any("rosbot-emulator" in e.text for e in examples_)
    if session.needs_robot and not starts_router:     # the rehearsal's robot side
        session.start(Example(block, 0, "papf launch robot", -1, True),
                      [PY, "-m", "papf", "launch", "robot", "--listen", session.endpoint])
    elif uses_router and not starts_router:
        session.start(Example(block, 0, "python -m papf.launch.router", -1, True),
                      [PY, "-m", "papf.launch.router", "--listen", session.endpoint])
    try:
        for ex in examples_:
            session.run(ex)
    finally:
        session.stop()
