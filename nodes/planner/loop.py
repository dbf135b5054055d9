"""Input pairing and staleness for the planner process (pure; no zenoh; wall time injected).

:class:`PlannerLoop` takes the node's inbox items (scan, odometry, tracks, goal) and
returns what to publish as ``[(topic, message), ...]``, in lockstep or realtime (the
protocol of docs/architecture.md). Used by the planner node (``nodes/planner/__main__.py``).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable

from common import runauth
from common.params import check_value
from common.units import LOCKSTEP_PAIR_TIMEOUT_S
from nodes.planner.core import NS_PER_S, Planner
from nodes.planner.settings import NODE
from schemas.messages import Goal, Objects, Odometry, PlannerState, PlannerStatus, Scan, Twist

ODOM_BUFFER = 64          # odometry messages kept for pairing (1.28 s at 50 Hz)
OBJECTS_BUFFER = 16       # object lists kept for pairing (1.6 s at 10 Hz)
LATE_PAIR_S = 1.0         # [s] wall time a scan waits for its partners before that is logged
STALE_REPEAT_S = 0.1      # [s] wall period of zero commands while scans are stale (realtime)
PLAN_HORIZON_S = 1.5      # [s] the realtime commands' plan (docs/link-driving.md, "The choice")


class PlannerLoop:
    """Pairs scans with odometry (and tracks), drops stale input, runs the :class:`Planner` (pure; no zenoh).

    - **lockstep** (default): ``scan(t)`` is paired with ``odom(t)`` (same stamp), and with
      ``objects(t)`` when the loop takes obstacle tracks (``objects=True``). Whichever
      arrives last triggers the cycle. A scan whose partners have not arrived after
      ``pair_timeout_s`` of wall time is answered with the newest older odometry (objects)
      if it is fresh (``<= stale_timeout_s`` of sim time older), else with a zero command
      (objects: none).
    - **realtime**: each scan is paired with the latest odometry (and objects); odometry
      older than ``stale_timeout_s`` (vs the scan stamp) -> zero command. No scan for
      ``stale_timeout_s`` of wall time -> a zero command every ``STALE_REPEAT_S``.
    - A goal -> :meth:`Planner.set_goal` and a ``ready`` status with the goal's stamp. With a
      run key (:mod:`common.runauth`), only a goal signed with it counts (others are dropped
      and counted in ``rejected_goals``), and every status is signed.
    - Every answered scan publishes ``cmd_vel`` (stamp = scan stamp), then ``planner/state``
      and ``planner/status``. With ``send_command`` the command goes out through it as soon as
      it exists (before the debug state is built; the returned list then holds the rest).
      With ``want_state`` (e.g. :meth:`common.transport.Node.listened`) false,
      ``planner/state`` is neither built nor returned: a debug topic nobody subscribes to
      costs nothing.
    """

    def __init__(self, planner: Planner, realtime: bool = False, stale_timeout_s: float = 0.5,
                 pair_timeout_s: float = LOCKSTEP_PAIR_TIMEOUT_S, log=None, run_key: bytes | None = None,
                 objects: bool = False, send_command: Callable[[Twist], None] | None = None,
                 want_state: Callable[[], bool] = lambda: True, plan_horizon_s: float = PLAN_HORIZON_S):
        check_value("stale_timeout", stale_timeout_s, NODE["stale_timeout"])
        check_value("plan_horizon", plan_horizon_s, NODE["plan_horizon"])
        if realtime:   # a real link: each command carries its short plan (lockstep: plain ones)
            planner.plan_steps = max(1, round(plan_horizon_s * NS_PER_S / planner.plan_dt_ns))
        check_value("pair_timeout", pair_timeout_s, NODE["pair_timeout"])
        self.planner, self.realtime, self.use_objects = planner, realtime, objects
        self.send_command, self.want_state = send_command, want_state
        self.stale_ns = int(stale_timeout_s * NS_PER_S)
        self.stale_s, self.pair_timeout_s = stale_timeout_s, pair_timeout_s
        self.log = log
        self.odoms: OrderedDict[int, Odometry] = OrderedDict()
        self.objects: OrderedDict[int, Objects] = OrderedDict()
        self.pending: list[tuple[Scan, float]] = []     # scans waiting for odom(t), arrival wall time
        self.last_scan_wall: float | None = None
        self.last_zero_wall = -1e18
        self.last_stamp = 0
        self.cycles = 0
        self.stale_cycles = 0
        self.run_key = run_key
        self.rejected_goals = 0

    # -- inputs ---------------------------------------------------------------
    def on_message(self, topic: str, msg, now: float) -> list:
        """One message on ``topic`` at wall time ``now`` [s] -> the (topic, message) pairs to publish."""
        return self._sign(self._on_message(topic, msg, now))

    def poll(self, now: float) -> list:
        """Time-driven work: overdue pairings (lockstep), stale scans (realtime)."""
        return self._sign(self._poll(now))

    def _sign(self, out: list) -> list:
        if self.run_key is None:
            return out
        return [(t, runauth.sign(m, self.run_key) if t == "planner/status" else m) for t, m in out]

    def _on_message(self, topic: str, msg, now: float) -> list:
        if topic == "goal" and isinstance(msg, Goal):
            if not runauth.verify(msg, self.run_key):
                self.rejected_goals += 1
                if self.log and self.rejected_goals <= 5:
                    self.log.warning("ignored a goal (%.2f, %.2f) that is not this run's",
                                     msg.x, msg.y)
                return []
            return [("planner/status", self.planner.set_goal(msg))]
        if topic == "odom" and isinstance(msg, Odometry):
            _store(self.odoms, msg, ODOM_BUFFER)
            return [] if self.realtime else self._release(now)
        if topic == "objects" and isinstance(msg, Objects) and self.use_objects:
            _store(self.objects, msg, OBJECTS_BUFFER)
            return [] if self.realtime else self._release(now)
        if topic == "scan" and isinstance(msg, Scan):
            self.last_scan_wall = now
            if self.realtime:
                return self._answer(msg, _latest(self.odoms), _latest(self.objects))
            self.pending.append((msg, now))
            return self._release(now)
        return []

    def _poll(self, now: float) -> list:
        out = self._release(now)
        if self.realtime and self.planner.goal is not None:
            since = None if self.last_scan_wall is None else now - self.last_scan_wall
            if (since is None or since > self.stale_s) and now - self.last_zero_wall >= STALE_REPEAT_S:
                self.last_zero_wall = now
                odom = _latest(self.odoms)
                stamp = odom.stamp_ns if odom is not None else self.last_stamp
                out.append(("cmd_vel", Twist(stamp_ns=stamp, v=0.0, w=0.0)))
        return out

    # -- helpers ----------------------------------------------------------------
    def _complete(self, t: int) -> bool:
        return t in self.odoms and (not self.use_objects or t in self.objects)

    def _release(self, now: float) -> list:
        """Answer pending scans that now have all their partners or waited too long."""
        out, keep = [], []
        for scan, arrived in sorted(self.pending, key=lambda p: p[0].stamp_ns):
            t = scan.stamp_ns
            if self._complete(t):
                if now - arrived > LATE_PAIR_S and self.log:   # where a held cycle waited
                    self.log.warning("scan %d waited %.2f s for its odometry/objects",
                                     t, now - arrived)
                out += self._answer(scan, self.odoms[t], self.objects.get(t))
            elif now - arrived > self.pair_timeout_s:
                odom, objects = _newest_upto(self.odoms, t), _newest_upto(self.objects, t)
                if self.log:
                    self.log.warning("no odom/objects with stamp %d after %.2f s; using %s / %s",
                                     t, now - arrived, "none" if odom is None else odom.stamp_ns,
                                     "none" if objects is None else objects.stamp_ns)
                out += self._answer(scan, odom, objects)
            else:
                keep.append((scan, arrived))
        self.pending = keep
        return out

    def _answer(self, scan: Scan, odom: Odometry | None, objects: Objects | None = None) -> list:
        self.cycles += 1
        self.last_stamp = scan.stamp_ns
        if odom is None or scan.stamp_ns - odom.stamp_ns > self.stale_ns:
            return self._stale(scan, odom)
        if objects is not None and scan.stamp_ns - objects.stamp_ns > self.stale_ns:
            objects = None
        cmd, finish = self.planner.command(scan, odom, objects)
        out = [("cmd_vel", cmd)]
        if self.send_command is not None:  # out now: the driver waits for it in lockstep
            self.send_command(cmd)
            out = []
        if not self.want_state():
            return [*out, ("planner/status", finish(False)[1])]
        state, status = finish()
        return [*out, ("planner/state", state), ("planner/status", status)]

    def _stale(self, scan: Scan, odom: Odometry | None) -> list:
        self.stale_cycles += 1
        age = "none" if odom is None else f"{(scan.stamp_ns - odom.stamp_ns) / NS_PER_S:.3f} s old"
        t = scan.stamp_ns
        state = "idle" if self.planner.goal is None else self.planner.state
        state = "driving" if state == "ready" else state
        debug = [("planner/state", PlannerState(stamp_ns=t, algorithm=self.planner.strategy.name,
                                                mode="stale"))] if self.want_state() else []
        return [("cmd_vel", Twist(stamp_ns=t, v=0.0, w=0.0)), *debug,
                ("planner/status", PlannerStatus(stamp_ns=t, state=state,
                                                 reason=f"stale odometry ({age}): stopped"))]


def _store(buffer: OrderedDict, msg, limit: int) -> None:
    buffer[msg.stamp_ns] = msg
    buffer.move_to_end(msg.stamp_ns)
    while len(buffer) > limit:
        buffer.popitem(last=False)


def _latest(buffer: OrderedDict):
    return max(buffer.values(), key=lambda m: m.stamp_ns) if buffer else None


def _newest_upto(buffer: OrderedDict, t: int):
    older = [m for m in buffer.values() if m.stamp_ns <= t]
    return max(older, key=lambda m: m.stamp_ns) if older else None
