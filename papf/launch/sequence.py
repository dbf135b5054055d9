"""The launcher's side of a run over its Zenoh session (docs/architecture.md, "Start and
end of a run"), shared by `papf run` and `papf launch`:

goal handshake -> ``run_started`` -> watch messages until an outcome -> figures at
``t_end`` -> ``run_ended`` (carrying the result as JSON, so recordings hold it).
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable

import zenoh

from common import runauth
from common.errors import SchemaError
from common.intake import Trust
from common.transport import round_robin
from common.units import StampGuard
from nodes.world_sim.loop import LOCKSTEP_FAULT
from papf.launch.linkwatch import LinkWatch
from papf.launch.outcome import MAX_FAULTS, NS, RunMonitor, RunResult
from papf.launch.supervisor import Supervisor
from schemas import Event, Keys, PlannerStatus
from schemas.keys import STAMP_ORDERED, TOPICS
from worlds import World
from worlds.messages import goal_message

log = logging.getLogger("papf.run")

GOAL_HANDSHAKE_S = 15.0  # [s wall] for the planner to acknowledge the goal
STALL_S = 20.0           # [s wall] no sim-clock progress for this long = the stack is stuck
FIGURES_S = 10.0         # [s wall] for battery/pose samples to reach t_end
CHECK_S = 0.05           # [s wall] period of the watch (node deaths, stall, progress, stop)
RECORDER_ACK_S = 15.0    # [s wall] for the recorder to close its file after run_ended
COALESCE_S = 0.01        # [s wall] the watch takes the message stream in batches this far apart
POLL_S = 0.005           # [s wall] while waiting for messages, look this often
CHANNEL_CAPACITY = 65536 # [samples] per topic between two looks (then Zenoh waits)
HEALTH_S = 1.0           # [s wall] for the nodes' health answers at the end of a run


class RunSequence:
    """One run driven over ``session``: subscriptions feed ``monitor`` on the caller's thread."""

    def __init__(self, session: zenoh.Session, keys: Keys, sup: Supervisor, monitor: RunMonitor,
                 pose_topic: str = "sim/pose", stop: Callable[[], bool] = lambda: False,
                 stall_s: float = STALL_S, run_key: bytes | None = None,
                 run_id: bytes | None = None, link: LinkWatch | None = None,
                 commands: bool = True):
        self.session, self.keys, self.sup, self.monitor = session, keys, sup, monitor
        self.link = link                     # a split run: the link to the robot, watched
        self.stop, self.stall_s = stop, stall_s
        self.run_key = run_key               # goals signed, statuses verified (common.runauth)
        # every put sealed, every sample of this run's processes only (common.intake)
        self.trust = Trust(run_key, run_id) if run_key is not None else Trust(None, None)
        self.run_id = run_id
        self.stamps = StampGuard(STAMP_ORDERED, restart_at_zero=False)
        self.dropped = 0                     # bad payloads, stamps and tags: not acted on
        self._key_of: dict[str, str] = {}    # topic -> its key expression (the seal covers it)
        self._handlers = {"clock": monitor.on_clock, "planner/status": monitor.on_status,
                          "events": monitor.on_event, "battery": monitor.on_battery,
                          "cmd_vel": monitor.on_cmd, pose_topic: monitor.on_pose,
                          "goal": monitor.on_goal}
        if not commands:   # a fleet's robot: no stop latency in its figures, no cmd_vel to watch
            del self._handlers["cmd_vel"]
        if pose_topic == "sim/pose":
            # the world simulator puts sim/pose(t) just before clock(t), at every instant: the pose
            # samples carry the sim time, and the launcher is not woken for clock as well
            del self._handlers["clock"]
            self._handlers[pose_topic] = lambda msg: (monitor.on_pose(msg),
                                                      monitor.on_time(msg.stamp_ns),
                                                      *(hook(msg) for hook in self._pose_hooks))
        self._pose_hooks: list[Callable] = []   # watch_poses
        self._faults_seen = 0                   # the monitor's faults looked at (_explain_held)
        self.watchers: list[Callable[[RunMonitor], None]] = []   # called every CHECK_S of the run
        if link is not None:   # the robot's clock is the laptop's ear; its reports its voice
            self._handlers["clock"] = lambda msg: (monitor.on_clock(msg), self._heard())
            self._handlers["link"] = link.on_health
        # Each topic's samples wait in Zenoh's own channel until the caller's thread drains
        # them (:meth:`drain`): no Python on Zenoh's thread, no wake per message — the
        # launcher watches 50 Hz streams to decide what changes at 10 Hz at most.
        self._channels: list[tuple[str, type, zenoh.Subscriber]] = []
        self._subs: list[zenoh.Subscriber] = []
        for topic in self._handlers:
            self._listen(keys.key(topic), topic, TOPICS[topic])

    def _heard(self) -> None:
        for kind, detail in self.link.heard(time.monotonic_ns()):
            self.event(kind, detail)

    def event(self, kind: str, detail: str) -> None:
        """An event of the launcher's on the run's clock (the link's, as the laptop sees it)."""
        log.warning("%s", detail)
        self.put(self.keys.events, Event(stamp_ns=max(self.monitor.clock_ns, 0), kind=kind,
                                         source="launcher", detail=detail))

    def _listen(self, key: str, topic: str, msg_type: type) -> None:
        self._key_of[topic] = key
        sub = self.session.declare_subscriber(key, zenoh.handlers.FifoChannel(CHANNEL_CAPACITY))
        self._channels.append((topic, msg_type, sub))
        self._subs.append(sub)

    def watch_key(self, key: str, msg_type: type, handler: Callable) -> None:
        """Also decode the full key ``key`` as ``msg_type`` and hand it to ``handler`` on the
        caller's thread (drained with the rest; a fleet's people)."""
        name = "@" + key
        self._handlers[name] = handler
        self._listen(key, name, msg_type)

    def watch_poses(self, hook: Callable) -> None:
        """Call ``hook(odometry)`` with every pose sample too (in sim; a fleet's separations)."""
        self._pose_hooks.append(hook)

    def put(self, key: str, msg) -> None:
        """Put ``msg`` on ``key``, sealed with the run's key and id."""
        payload = msg.to_bytes()
        attachment = self.trust.seal(key, payload)
        if attachment is None:
            self.session.put(key, payload)
        else:
            self.session.put(key, payload, attachment=attachment)

    def _accept(self, topic: str, msg_type: type, payload: bytes, attachment: bytes | None = None):
        """The decoded message, or None (a bad payload, seal, stamp or tag: counted, not
        acted on; refused seals also per topic and reason in ``trust.refused``)."""
        try:
            msg = msg_type.from_bytes(payload)
        except SchemaError:
            self.dropped += 1
            return None
        verdict = self.trust.check(topic, self._key_of[topic], payload, attachment, msg)
        if verdict != "ok":
            self.dropped += 1
            if not self.trust.expected(verdict) and self.trust.alarming() in (1, 10, 100, 1000):
                log.warning("refused samples not sealed by this run's processes: %s",
                            self.trust.counts())
            return None
        if self.stamps.check(topic, msg) or (
                topic in ("planner/status", "goal") and not runauth.verify(msg, self.run_key)):
            self.dropped += 1
            return None
        return msg

    def _take(self) -> list[tuple[str, object]]:
        """Every waiting sample, decoded and fed to the monitor; one per topic in turn, so
        streams published in step come out in step."""
        got = []
        for topic, msg_type, payload, attachment in round_robin(self._channels):
            msg = self._accept(topic, msg_type, payload, attachment)
            if msg is not None:
                self._handlers[topic](msg)
                got.append((topic, msg))
        return got

    def drain(self, timeout_s: float) -> list[tuple[str, object]]:
        """Feed waiting messages to the monitor; if none, look every :data:`POLL_S` for up to
        ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while True:
            got = self._take()
            if got or time.monotonic() >= deadline or not self._channels:
                return got
            time.sleep(POLL_S)

    # -- the sequence ---------------------------------------------------------
    def handshake(self, world: World) -> bool:
        """Publish the goal every 0.5 s until the planner answers ``ready``."""
        goal = runauth.sign(goal_message(world), self.run_key)
        deadline = time.monotonic() + GOAL_HANDSHAKE_S
        while time.monotonic() < deadline and not self.stop() and not self.sup.dead():
            self.put(self.keys.goal, goal)   # sealed afresh each time: a new seq
            t_next = time.monotonic() + 0.5
            while time.monotonic() < t_next:
                if any(t == "planner/status" and isinstance(m, PlannerStatus) and m.state == "ready"
                       for t, m in self.drain(0.05)):
                    return True
        self.monitor.fail("interrupted" if self.stop() else self.sup.death_reason() or
                          f"the planner never acknowledged the goal within {GOAL_HANDSHAKE_S:g} s")
        return False

    def start(self, detail: str) -> None:
        self.put(self.keys.events, Event(stamp_ns=0, kind="run_started", source="launcher",
                                         detail=detail))

    def until_outcome(self, progress=None, goal_xy: tuple[float, float] | None = None) -> None:
        """Watch until the monitor has an outcome; a dead node, a stall or a stop is one too."""
        m = self.monitor
        last_clock, last_change = m.clock_ns, time.monotonic()
        next_check = last_change
        while not m.done:
            if self.drain(0.05) and not m.done:
                time.sleep(COALESCE_S)   # let the next messages gather: one wake per batch
            now = time.monotonic()
            if now < next_check:  # the watch below at most every CHECK_S, not per message
                continue
            next_check = now + CHECK_S
            if m.clock_ns != last_clock:
                last_clock, last_change = m.clock_ns, now
            for watcher in self.watchers:
                watcher(m)
            self._explain_held()
            state = m.status.state if m.status else ""
            if self.link is not None:
                for kind, detail in self.link.tick(time.monotonic_ns()):
                    self.event(kind, detail)
                state = f"{state}  {self.link.text()}".rstrip()
            if progress is not None and goal_xy is not None:
                progress.update(m.clock_ns / NS, m.distance_to(*goal_xy),
                                m.batteries[-1].charge_used_mAh if m.batteries else 0.0, state)
            if self.stop():
                m.fail("interrupted")
            elif self.sup.dead():
                self._on_node_death()
            elif now - last_change > self.stall_s:
                m.fail(f"sim time stuck at {m.clock_ns / NS:.2f} s for {self.stall_s:g} s "
                       "(a node is hung, or the link to the base driver is lost)")
        self._wait_for_figures()

    def _explain_held(self) -> None:
        """After the world simulator's lockstep wait ran out (its ``node_fault``): where the
        cycle waits, from every node's health answer (the stamp each last took and put per
        topic), logged and added to the run's faults — the node whose input has the scan's
        stamp and whose output has not is the one holding it."""
        m = self.monitor
        new, self._faults_seen = m.faults[self._faults_seen:], len(m.faults)
        if not any(LOCKSTEP_FAULT in fault for fault in new):
            return
        started = [c.name for c in self.sup.children if c.name not in ("router", "recorder")]
        where = where_held(self.health(), started)
        log.warning("lockstep held: %s", where)
        if len(m.faults) < MAX_FAULTS:
            m.faults.append(f"launcher: the nodes' last stamps: {where}")
            self._faults_seen = len(m.faults)

    def _on_node_death(self) -> None:
        """A node died: the figures freeze at its last output (the meter's last battery, the
        planner's last status, else the clock now), never past the timeout, and the reason
        names it. After a planner's death the robot's stop is still watched (stop latency)."""
        m = self.monitor
        dead = self.sup.dead()[0].name
        at = {"energy_meter": m.last_stamp("battery"), "planner": m.last_stamp("status")}.get(dead)
        m.fail(self.sup.death_reason(), at)
        m.reason += f" (figures frozen at {(m.t_end_ns or 0) / NS:.2f} s)"
        if dead != "planner":
            return
        deadline = time.monotonic() + 10.0  # the driver's lockstep timeout + its watchdog
        while time.monotonic() < deadline and not (m.watchdog_stop_ns and m.robot_stopped()):
            self.drain(0.05)

    def wait_for_figures(self) -> None:
        """Wait (at most FIGURES_S) until battery and pose samples reach ``t_end``."""
        self._wait_for_figures()

    def _wait_for_figures(self) -> None:
        deadline = time.monotonic() + FIGURES_S
        while not self.monitor.figures_complete() and time.monotonic() < deadline:
            if self.stop() or any(c.name in ("energy_meter", "base_driver")
                                  for c in self.sup.dead()):
                break
            self.drain(0.05)
        if not self.monitor.figures_complete():
            log.warning("figures at t_end=%.2f s incomplete (battery/pose samples missing)",
                        (self.monitor.t_end_ns or 0) / NS)

    def end(self, result: RunResult, wait_recorder: bool = True, stamp_ns: int | None = None) -> bool:
        """``run_ended`` with the result as JSON; then, if a recorder runs, wait (at most
        :data:`RECORDER_ACK_S`) for its ``recording_closed``: its file is then complete.
        Stop listening. False if a recorder runs and did not acknowledge. Nothing is
        published when this run's router died: what the session reaches then is not ours.

        Before ``run_ended`` the nodes' health (:meth:`common.transport.Node.health`) goes
        into ``result.refused``: what each process refused (unsealed, replayed, another
        run's); after it, the recorder's own account into ``result.recording``. A recording
        that stopped early — the recorder froze, died, or never confirmed its file — makes
        the run ``failed`` (exit 6), its reason saying so and what the run itself was:
        the user asked for a record of the run and has none."""
        if any(c.name == "router" for c in self.sup.dead()):
            for sub in self._subs:
                sub.undeclare()
            self._subs.clear()
            return False
        if stamp_ns is None:   # a fleet's: every robot's run_ended at the fleet's end
            stamp_ns = self.monitor.t_end_ns or max(self.monitor.clock_ns, 0)
        result.run_id = self.run_id.hex() if self.run_id else ""
        result.refused = self.refusals()
        self.put(self.keys.events, Event(stamp_ns=stamp_ns, kind="run_ended", source="launcher",
                                         detail=json.dumps(result.to_json())))
        closed = self._wait_for_recorder() if wait_recorder else True
        if wait_recorder:
            self._judge_recording(result, closed)
        for sub in self._subs:
            sub.undeclare()
        self._subs.clear()
        return closed

    def refusals(self) -> dict:
        """``{process: {topic: {reason: n}}}``: the launcher's and every node's refusals
        (their health queryables, :data:`HEALTH_S` at most) — unsealed, replayed, another
        run's, and ``malformed`` (undecodable or a bad stamp) — those with any only."""
        out = {"launcher": self.trust.counts()} if self.trust.refused else {}
        for name, health in self.health().items():
            counts = {t: dict(why) for t, why in (health.get("refused") or {}).items()}
            for topic, n in (health.get("bad") or {}).items():   # undecodable, bad stamps
                counts.setdefault(topic, {})["malformed"] = n
            if counts:
                out[name] = counts
        return out

    def health(self, node: str = "*") -> dict[str, dict]:
        """The health answers of this namespace's nodes (``node``: one, or ``*``)."""
        prefix = self.keys.key("health/")
        out = {}
        try:
            for reply in self.session.get(self.keys.key(f"health/{node}"), timeout=HEALTH_S):
                if reply.ok is None:
                    continue
                try:
                    data = json.loads(reply.ok.payload.to_bytes())
                except ValueError:
                    continue
                if isinstance(data, dict):
                    out[str(reply.ok.key_expr)[len(prefix):]] = data
        except Exception as exc:   # a closing session: no health, the run's figures stand
            log.debug("health query failed: %s", exc)
        return out

    def _judge_recording(self, result: RunResult, closed: bool) -> None:
        recorder = [c for c in self.sup.children if c.name == "recorder"]
        if not recorder:
            return
        account = self.health("recorder").get("recorder", {}).get("recording") if closed else None
        if closed and account:
            result.recording = account
            return
        code = recorder[0].returncode
        why = (f"the recorder exited with code {code}" if code is not None else
               f"the recorder did not close its file within {RECORDER_ACK_S:g} s (frozen?)")
        result.recording = {"complete": False, "reason": why}
        if result.outcome == "failed":   # already failed: by the recorder's death, or else
            if not result.reason.startswith("recorder "):
                result.reason += f"; the recording stopped early too: {why}"
            return
        ran = f"{result.outcome} at {result.sim_time_s:.2f} s"
        result.outcome = "failed"
        result.reason = (f"the recording stopped early: {why}; the run itself: {ran} "
                         f"{result.reason}").strip()

    def _wait_for_recorder(self) -> bool:
        recorder = [c for c in self.sup.children if c.name == "recorder"]
        if not recorder:
            return True
        deadline = time.monotonic() + RECORDER_ACK_S
        while time.monotonic() < deadline and recorder[0].returncode is None:
            if any(t == "events" and m.kind == "recording_closed" and m.source == "recorder"
                   for t, m in self.drain(0.05)):
                return True
        log.warning("the recorder did not confirm its file closed within %g s%s", RECORDER_ACK_S,
                    f" (it exited with code {recorder[0].returncode})"
                    if recorder[0].returncode is not None else "")
        return False


def where_held(health: dict[str, dict], started: list[str] = ()) -> str:
    """``base_driver took cmd_vel 47.00; put odom 47.10, … | planner took …``: the stamps
    [s] each node last took and put per topic (its health answer's ``heard`` and ``sent``),
    and which of the ``started`` nodes did not answer (frozen, or busy past the wait)."""
    def stamps(verb: str, topics: dict) -> str:
        said = ", ".join(f"{t} {ns / NS:.2f}" for t, ns in sorted(topics.items())
                         if isinstance(ns, int) and ns >= 0)
        return f"{verb} {said}" if said else ""

    parts = []
    for name in sorted(health):
        h = health[name]
        said = "; ".join(x for x in (stamps("took", h.get("heard") or {}),
                                     stamps("put", h.get("sent") or {})) if x)
        peers = h.get("peers")
        linked = f" ({peers} peer links)" if isinstance(peers, int) else ""
        parts.append(f"{name}{linked} {said or 'nothing'}")
    silent = sorted(set(started) - set(health))
    if silent:
        parts.append("no answer from " + ", ".join(silent))
    return " | ".join(parts) or "no node answered"
