"""A laptop that dies and comes back (issue 30, item 4): find the run where it is, then resume it
or start a new one — as the user said, never by accident.

The robot side outlives the laptop: its base driver keeps the run's clock and run id, and its
watchdog has stopped the robot. It answers ``<ns>/run/state`` (sealed: :mod:`common.seal`)
with the run it is in (:func:`robot_run`). The laptop's launcher keeps a *journal* of its run
beside its key (:func:`journal_path`, rewritten every :data:`JOURNAL_EVERY_S`: run id, goal,
charge, path, the last battery stamp) and removes it when the run ends. A new laptop launch
then:

- finds the robot in no run: a new run, as always;
- finds the robot still in a run: refuses (exit 2, one line) unless told ``--resume`` (the
  same run: its id, the robot's clock going on, the journal's goal, the meter going on from
  the journal's charge — the time without a meter is metered at standstill — and the path
  going on from the journal's) or ``--new-run`` (a new run id, a clock from 0 and a fresh
  meter, starting where the robot stands: the driver keeps the world frame it had, so the
  robot drives from there to the goal and never re-drives the course from its start).
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import zenoh

from common import runauth, seal
from common.errors import ConfigError
from common.intake import Trust
from schemas import Keys

STATE_S = 3.0           # [s wall] for the robot's run state to answer
JOURNAL_EVERY_S = 0.25  # [s wall] the journal is rewritten this often during a run
AFTER_CRASH = ("refuse", "resume", "new")


@dataclass
class RobotRun:
    """What the robot's driver says about its run."""

    run: str            # hex; "" = none
    running: bool
    t_ns: int           # run time now
    x: float = float("nan")
    y: float = float("nan")


def state_answer(trust: Trust, key_expr: str, run: str, running: bool, t_ns: int,
                 pose: tuple[float, float] | None) -> tuple[bytes, bytes | None]:
    """The driver's answer to ``<ns>/run/state``: payload and its seal."""
    x, y = pose if pose is not None else (None, None)
    payload = json.dumps({"run": run, "running": running, "t_ns": t_ns, "x": x, "y": y}).encode()
    return payload, trust.seal(key_expr, payload)


def robot_run(session: zenoh.Session, keys: Keys, key: bytes) -> RobotRun | None:
    """The robot driver's run (its sealed answer), or None (no driver answers, or none sealed
    with ``key``: a robot that is not up yet has no run to join)."""
    key_expr = keys.key("run/state")
    opener = seal.Opener(key, None)
    for reply in session.get(key_expr, timeout=STATE_S):
        if reply.ok is None:
            continue
        payload = reply.ok.payload.to_bytes()
        att = reply.ok.attachment
        verdict, _ = opener.check(key_expr, payload, None if att is None else att.to_bytes())
        if verdict != seal.OK:
            continue
        try:
            d = json.loads(payload)
            return RobotRun(str(d.get("run") or ""), bool(d.get("running")), int(d.get("t_ns") or 0),
                            _num(d.get("x")), _num(d.get("y")))
        except (ValueError, TypeError):
            continue
    return None


def _num(v) -> float:
    return float(v) if isinstance(v, (int, float)) else float("nan")


# -- the journal ------------------------------------------------------------------------------
@dataclass
class Journal:
    """A run as its launcher last saw it (enough to resume it)."""

    run: str
    world: str
    goal: tuple[float, float, float]
    charge_mAh: float = 0.0
    energy_J: float = 0.0
    soc: float = 1.0
    battery_ns: int = -1          # stamp of the battery sample those figures are of (-1: none)
    path_m: float = 0.0
    motion_start_ns: int | None = None
    t_ns: int = 0
    x: float | None = None        # [m] the newest pose sample those figures are of
    y: float | None = None


def journal_path(namespace: str) -> Path:
    return runauth.key_file(namespace).with_suffix(".run.json")


def write_journal(namespace: str, journal: Journal) -> None:
    """Replace the journal (a temporary file beside it, renamed: a crash leaves the old one)."""
    path = journal_path(namespace)
    tmp = path.with_suffix(".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0), 0o600)
    with os.fdopen(fd, "w") as f:
        json.dump(asdict(journal), f)
    os.replace(tmp, path)


def read_journal(namespace: str) -> Journal | None:
    try:
        d = json.loads(journal_path(namespace).read_text())
        d["goal"] = tuple(float(v) for v in d["goal"])
        return Journal(**d)
    except (OSError, ValueError, TypeError, KeyError):
        return None


def drop_journal(namespace: str, run: str) -> None:
    """Remove the journal if it is ``run``'s (the run ended: nothing to resume)."""
    j = read_journal(namespace)
    if j is not None and j.run == run:
        try:
            journal_path(namespace).unlink()
        except OSError:
            pass


class JournalWriter:
    """Rewrites the journal from a :class:`~papf.launch.outcome.RunMonitor` now and then."""

    def __init__(self, namespace: str, base: Journal, clock=time.monotonic):
        self.namespace, self.base, self.clock = namespace, base, clock
        self._next = 0.0

    def update(self, monitor) -> None:
        now = self.clock()
        if now < self._next:
            return
        self._next = now + JOURNAL_EVERY_S
        b = monitor.batteries[-1] if monitor.batteries else None
        j = self.base
        if b is not None:
            j.charge_mAh, j.energy_J, j.soc, j.battery_ns = (b.charge_used_mAh, b.energy_J,
                                                             b.soc, b.stamp_ns)
        j.path_m = monitor.path_so_far()
        j.x, j.y = monitor.last_xy() or (j.x, j.y)
        j.motion_start_ns = monitor.motion_start_ns()
        j.t_ns = max(monitor.clock_ns, 0)
        j.goal = monitor.goal or j.goal
        try:
            write_journal(self.namespace, j)
        except OSError:
            pass   # a journal is a help for a crash, never a reason to stop a run


# -- the decision -----------------------------------------------------------------------------
def decide(robot: RobotRun | None, after_crash: str, namespace: str,
           new_run: str) -> tuple[str, Journal | None]:
    """(the run id to drive, the journal to resume from or None). ConfigError (one line) when
    the robot is in a run and the user did not say what to do, or asked for what cannot be."""
    in_run = robot is not None and robot.running and robot.run
    if not in_run:
        if after_crash == "resume":
            raise ConfigError("--resume: the robot is in no run (nothing to resume); launch "
                              "without it for a new run")
        return new_run, None
    where = "" if robot.x != robot.x else f", at ({robot.x:.2f}, {robot.y:.2f})"
    if after_crash == "refuse":
        raise ConfigError(
            f"the robot is still in run {robot.run} ({robot.t_ns / 1e9:.1f} s in{where}), started "
            "by a launcher that is gone: give --resume to go on with that run (same clock, "
            "charge and goal) or --new-run to start a new run from where the robot stands")
    if after_crash == "new":
        return new_run, None
    journal = read_journal(namespace)
    if journal is None or journal.run != robot.run:
        raise ConfigError(
            f"--resume: this host has no journal of run {robot.run} ({journal_path(namespace)}"
            f"{' holds run ' + journal.run if journal else ' is missing'}); give --new-run")
    return robot.run, journal
