"""``papf goal X Y``: send the planner a goal, optionally start the run, follow it to an outcome.

:func:`send_goal` does the launcher's handshake (docs/architecture.md, "Start and end of a
run") and follows ``planner/status`` to an outcome and its exit code (:class:`GoalResult`).
Used by ``papf goal``.
"""

from __future__ import annotations

import math
import queue
import time
from collections.abc import Callable
from dataclasses import dataclass

import zenoh

from common import runauth
from common.outcomes import EXIT_CODES
from papf.console.progress import DecileProgress
from schemas import Event, Goal, Keys, PlannerStatus

HANDSHAKE_S = 15.0     # [s wall] for a planner to acknowledge the goal
REPEAT_S = 0.5         # [s wall] goal repeated this often until acknowledged
FINAL = {"reached": "reached", "stagnated": "stagnated", "failed": "failed"}


@dataclass
class GoalResult:
    outcome: str          # acknowledged | reached | stagnated | failed | collision | timeout |
    reason: str           # no_planner | interrupted
    distance_m: float     # last distance to the goal the planner reported [m] (nan: none)

    @property
    def exit_code(self) -> int:
        """``papf goal``'s exit code of this outcome (0 acknowledged, else EXIT_CODES)."""
        if self.outcome == "superseded":
            return 6
        if self.outcome == "acknowledged":
            return 0
        if self.outcome == "interrupted":
            return 130
        return EXIT_CODES.get(self.outcome, 6)


WATCH_MAX = 10_000   # [messages] waiting to be looked at (a peer's flood: the rest dropped)


class _Watch:
    def __init__(self, session: zenoh.Session, keys: Keys):
        self.q: queue.Queue = queue.Queue(maxsize=WATCH_MAX)
        self.dropped = 0
        self.subs = [session.declare_subscriber(keys.planner_status, self._cb(PlannerStatus)),
                     session.declare_subscriber(keys.events, self._cb(Event)),
                     session.declare_subscriber(keys.goal, self._cb(Goal))]

    def _cb(self, msg_type):
        def on_sample(sample: zenoh.Sample) -> None:
            try:
                self.q.put_nowait(msg_type.from_bytes(sample.payload.to_bytes()))
            except queue.Full:   # memory bounded under a flood
                self.dropped += 1
            except Exception:  # a bad payload is not this command's business
                pass
        return on_sample

    def next(self, timeout_s: float):
        try:
            return self.q.get(timeout=max(timeout_s, 0.0))
        except queue.Empty:
            return None

    def close(self) -> None:
        for s in self.subs:
            s.undeclare()


def send_goal(session: zenoh.Session, keys: Keys, x: float, y: float, tolerance: float = 0.1, *,
              start_run: bool = False, wait: bool = True, timeout_s: float = 0.0,
              out: Callable[[str], None] = print, progress: bool | None = None,
              stop: Callable[[], bool] = lambda: False) -> GoalResult:
    """Send a goal to ``x``, ``y`` [m] and follow it. ``timeout_s`` 0: wait as long as it takes.

    The same handshake as the launcher's (docs/architecture.md, "Start and end of a run"):
    publish ``<ns>/goal`` every 0.5 s until the planner answers ``planner/status`` ``ready``;
    with ``start_run`` then publish ``events`` ``run_started`` (what a world simulator started alone
    waits for). Then, unless told not to wait, follow ``planner/status`` until ``reached``
    (exit 0), ``stagnated`` (3) or ``failed`` (6); a ``collision`` event gives 4,
    ``timeout_s`` without an outcome 5, and another goal on ``<ns>/goal`` (someone re-targeted
    the planner: its statuses are no longer about this goal) 6. In a session started by ``papf launch`` the launcher
    keeps deciding the run's outcome; this command only steers the planner.
    """
    watch = _Watch(session, keys)
    try:
        key = runauth.read_key(keys.ns)   # a launched session's key, if any
        run = runauth.read_run(keys.ns)   # and its run: the planner takes that run's goals only
        goal = runauth.sign(Goal(stamp_ns=0, x=float(x), y=float(y), tolerance=float(tolerance)),
                            key)
        acked, heard = _handshake(session, keys, goal, watch, stop, key, run)
        if not acked:
            return GoalResult("interrupted" if stop() else "no_planner",
                              "interrupted" if stop() else _unanswered(keys, heard, key), math.nan)
        out(f"goal ({x:g}, {y:g}) ±{tolerance:g} m acknowledged by the planner")
        if start_run:
            runauth.sealed_put(session, keys.events, Event(
                stamp_ns=0, kind="run_started", source="papf-goal",
                detail=f"goal=({x:g},{y:g})").to_bytes(), key, run)
            out(f"run_started published on {keys.events}")
        if not wait:
            return GoalResult("acknowledged", "", math.nan)
        return _follow(watch, goal, timeout_s, out, progress, stop)
    finally:
        watch.close()


def _handshake(session, keys: Keys, goal: Goal, watch: _Watch, stop, key: bytes | None = None,
               run: bytes | None = None) -> tuple[bool, bool]:
    """(the planner acknowledged the goal, a planner's status was heard at all). Each put is
    sealed afresh (a new seq: common.seal) with the launch's key and run."""
    deadline = time.monotonic() + HANDSHAKE_S
    heard = False
    while time.monotonic() < deadline and not stop():
        runauth.sealed_put(session, keys.goal, goal.to_bytes(), key, run)
        t_next = time.monotonic() + REPEAT_S
        while (left := t_next - time.monotonic()) > 0:
            msg = watch.next(min(left, 0.05))
            heard = heard or isinstance(msg, PlannerStatus)
            if isinstance(msg, PlannerStatus) and msg.state == "ready":
                return True, heard
    return False, heard


def _unanswered(keys: Keys, heard: bool, key: bytes | None) -> str:
    """Why no planner acknowledged the goal, and what to do."""
    if not heard:
        return (f"no planner answered on {keys.planner_status} within {HANDSHAKE_S:g} s "
                "(is one running? papf launch …, python -m nodes.planner)")
    if key is None:
        return (f"the planner on {keys.planner_status} is running but ignores goals not signed "
                f"with its run's key, and this user has none for namespace {keys.ns!r} "
                f"({runauth.key_file(keys.ns)}): steer runs started by this user with "
                "papf run --realtime or papf launch (a lockstep papf run takes no new goal)")
    return (f"the planner on {keys.planner_status} is running but ignored the goal: the key in "
            f"{runauth.key_file(keys.ns)} is not its run's (a run of another launcher?)")


def _follow(watch: _Watch, goal: Goal, timeout_s: float, out, progress: bool | None,
            stop) -> GoalResult:
    deadline = time.monotonic() + timeout_s if timeout_s > 0 else math.inf
    dist = math.nan
    with DecileProgress("to the goal", enabled=progress) as bar:
        while not stop():
            if time.monotonic() > deadline:
                return GoalResult("timeout", f"no outcome within {timeout_s:g} s", dist)
            msg = watch.next(0.1)
            if isinstance(msg, Event) and msg.kind == "collision":
                return GoalResult("collision", msg.detail or "collision", dist)
            if isinstance(msg, Goal) and (msg.x, msg.y, msg.tolerance) != (goal.x, goal.y,
                                                                          goal.tolerance):
                return GoalResult("superseded", f"another goal ({msg.x:g}, {msg.y:g}) was sent "
                                  "to the planner; its statuses are no longer about this one", dist)
            if not isinstance(msg, PlannerStatus):
                continue
            if not math.isnan(msg.distance_to_goal):
                dist = msg.distance_to_goal
                bar.distance(dist, f"{msg.state}, {dist:.2f} m to go")
            if msg.state in FINAL:
                out(f"{msg.state}: {msg.reason}" if msg.reason else msg.state)
                return GoalResult(msg.state, msg.reason, dist)
    return GoalResult("interrupted", "interrupted", dist)
