"""`papf run`: start the whole stack as processes, drive to an outcome, stop everything.

Sequence (docs/architecture.md): router -> nodes -> liveliness -> goal handshake ->
run_started -> watch messages until an outcome -> figures at ``t_end`` -> stop.
"""

from __future__ import annotations

import json
import logging
import queue
import sys
import time
from dataclasses import dataclass, field

import zenoh

from papf.monitor import NS, RunMonitor, RunResult
from papf.progress import RunProgress
from papf.supervisor import Supervisor, free_port, port_in_use, wait_port
from papf.transport import wait_alive, zenoh_config
from schemas import Event, Goal, Keys, PlannerStatus
from schemas.keys import TOPICS
from worlds import World, load_world, world_path

log = logging.getLogger("papf.run")

DEFAULT_PORT = 7447
STALL_S = 20.0  # [s wall] no sim-clock progress for this long = the stack is stuck


@dataclass
class RunConfig:
    world: str
    planner: str = "apf"
    seed: int = 0
    timeout_s: float = 300.0           # [s sim time]
    realtime: bool = False
    record: str | None = None
    port: int | None = None            # None: 7447, or a free port if 7447 is taken
    namespace: str = "rosbot"
    planner_args: list[str] = field(default_factory=list)   # e.g. ["--set", "v_max=0.3"]
    energy_model: str = "motor"
    stop_on_collision: bool = True
    verbose: bool = False
    progress: bool | None = None       # None: when stderr is a terminal
    startup_timeout_s: float = 60.0    # [s wall] for every node to become alive
    lockstep_timeout_s: float = 2.0    # [s wall] driver waits this long for a command
    extra_node_args: dict[str, list[str]] = field(default_factory=dict)
    zenoh_mode: str = "client"         # nodes' Zenoh mode: client (via the router) or peer


def node_commands(cfg: RunConfig, world_file: str, endpoint: str) -> dict[str, list[str]]:
    """argv of every node process of a sim run, in start order."""
    py = [sys.executable, "-m"]
    z = ["--connect", endpoint, "--namespace", cfg.namespace]
    if cfg.zenoh_mode == "peer":  # peers also talk directly: one loopback hop, not two
        z += ["--mode", "peer", "--listen", "tcp/127.0.0.1:0"]
    rt = ["--realtime"] if cfg.realtime else []
    cmds: dict[str, list[str]] = {}
    if cfg.record:
        cmds["recorder"] = [*py, "nodes.recorder", *z, "--out", cfg.record,
                            "--meta", f"world={cfg.world}", "--meta", f"planner={cfg.planner}",
                            "--meta", f"seed={cfg.seed}",
                            "--meta", f"planner_args={' '.join(cfg.planner_args)}",
                            "--meta", f"energy_model={cfg.energy_model}",
                            "--meta", f"timeout_s={cfg.timeout_s:g}"]
    cmds["energy_meter"] = [*py, "nodes.energy_meter", *z, "--model", cfg.energy_model]
    cmds["planner"] = [*py, "nodes.planner", *z, "--planner", cfg.planner, *rt, *cfg.planner_args]
    cmds["lidar_sim"] = [*py, "nodes.lidar_sim", *z, "--world", world_file, "--seed", str(cfg.seed)]
    cmds["base_driver"] = [*py, "nodes.base_driver", *z, "--driver", "sim", "--world", world_file,
                           "--seed", str(cfg.seed), "--lockstep-timeout",
                           str(cfg.lockstep_timeout_s), *rt]
    for name, extra in cfg.extra_node_args.items():
        cmds[name] = [*cmds[name], *extra]
    return cmds


def _show_line(verbose: bool):
    keys = ("WARNING", "ERROR", "CRITICAL", "Traceback", "Error", "error:")
    return lambda name, line: verbose or any(k in line for k in keys)


class _Watch:
    """The launcher's own Zenoh subscriptions, feeding a queue drained on the main thread."""

    TOPICS_WATCHED = ("clock", "planner/status", "events", "battery", "sim/pose", "cmd_vel")

    def __init__(self, session: zenoh.Session, keys: Keys):
        self.q: queue.Queue = queue.Queue()
        self.subs = [session.declare_subscriber(keys.key(t), self._cb(t)) for t in self.TOPICS_WATCHED]

    def _cb(self, topic: str):
        msg_type = TOPICS[topic]

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                self.q.put((topic, msg_type.from_bytes(sample.payload.to_bytes())))
            except Exception:  # garbage on a key is the nodes' problem, not the launcher's
                pass
        return on_sample

    def drain(self, monitor: RunMonitor, timeout_s: float) -> list[tuple[str, object]]:
        """Feed queued messages to the monitor; return them (for the caller's own use)."""
        handlers = {"clock": monitor.on_clock, "planner/status": monitor.on_status,
                    "events": monitor.on_event, "battery": monitor.on_battery,
                    "sim/pose": monitor.on_pose, "cmd_vel": monitor.on_cmd}
        got = []
        try:
            item = self.q.get(timeout=timeout_s)
            while True:
                handlers[item[0]](item[1])
                got.append(item)
                item = self.q.get_nowait()
        except queue.Empty:
            return got

    def close(self) -> None:
        for s in self.subs:
            s.undeclare()


def run(cfg: RunConfig) -> RunResult:
    """Run the whole stack once; always stops every process it started."""
    world = load_world(cfg.world)  # WorldError before anything starts
    world_file = str(world_path(cfg.world))
    port = cfg.port or (DEFAULT_PORT if not port_in_use(DEFAULT_PORT) else free_port())
    if cfg.port is None and port != DEFAULT_PORT:
        log.warning("port %d is in use; the embedded router listens on %d instead",
                    DEFAULT_PORT, port)
    endpoint = f"tcp/127.0.0.1:{port}"
    wall0 = time.monotonic()
    monitor = RunMonitor(cfg.timeout_s, cfg.stop_on_collision)
    keys = Keys(cfg.namespace)
    with Supervisor(show=_show_line(cfg.verbose), last=("recorder", "router")) as sup:
        sup.start("router", [sys.executable, "-m", "papf.router", "--listen", endpoint])
        if not wait_port(port, 15.0, abort=lambda: bool(sup.dead())):
            monitor.fail(f"the embedded router did not come up on {endpoint}: "
                         + " | ".join(sup.children[0].tail))
            return monitor.result(cfg.planner, world.name, cfg.seed, time.monotonic() - wall0)
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            watch = _Watch(session, keys)
            try:
                _drive(cfg, world, world_file, endpoint, sup, session, keys, watch, monitor)
            finally:
                watch.close()
                # The result rides on run_ended, so a recording carries its own outcome.
                result = monitor.result(cfg.planner, world.name, cfg.seed, time.monotonic() - wall0)
                session.put(keys.events, Event(
                    stamp_ns=monitor.t_end_ns or max(monitor.clock_ns, 0), kind="run_ended",
                    source="launcher", detail=json.dumps(result.to_json())).to_bytes())
    result.wall_time_s = time.monotonic() - wall0
    return result


def _drive(cfg: RunConfig, world: World, world_file: str, endpoint: str, sup: Supervisor,
           session: zenoh.Session, keys: Keys, watch: _Watch, monitor: RunMonitor) -> None:
    commands = node_commands(cfg, world_file, endpoint)
    for name, argv in commands.items():
        sup.start(name, argv)
    missing = wait_alive(session, keys, commands, cfg.startup_timeout_s,
                         abort=lambda: bool(sup.dead()))
    if missing or sup.dead():
        monitor.fail(_death_reason(sup) or f"nodes not alive after {cfg.startup_timeout_s:g} s: "
                     f"{', '.join(sorted(missing))}")
        return
    if not _handshake_goal(session, keys, world, watch, monitor, sup):
        return
    session.put(keys.events, Event(stamp_ns=0, kind="run_started", source="launcher",
                                   detail=f"world={world.name} planner={cfg.planner} "
                                          f"seed={cfg.seed}").to_bytes())
    _watch_until_outcome(cfg, world, sup, watch, monitor)


def _death_reason(sup: Supervisor) -> str:
    dead = sup.dead()
    if not dead:
        return ""
    c = dead[0]
    tail = " | ".join(list(c.tail)[-6:])
    return f"{c.name} exited with code {c.returncode}: {tail}"


def _handshake_goal(session, keys, world, watch, monitor, sup) -> bool:
    """Publish the goal until the planner answers `ready` (docs/architecture.md step 2)."""
    goal = Goal(stamp_ns=0, x=world.goal[0], y=world.goal[1], tolerance=world.tolerance)
    deadline = time.monotonic() + 15.0
    while time.monotonic() < deadline:
        session.put(keys.goal, goal.to_bytes())
        t_next = time.monotonic() + 0.5
        while time.monotonic() < t_next:
            for topic, msg in watch.drain(monitor, 0.05):
                if topic == "planner/status" and isinstance(msg, PlannerStatus) and msg.state == "ready":
                    return True
            if sup.dead():
                monitor.fail(_death_reason(sup))
                return False
    monitor.fail("the planner never acknowledged the goal (no 'ready' status within 15 s)")
    return False


def _watch_until_outcome(cfg, world, sup, watch, monitor) -> None:
    progress = RunProgress(cfg.progress, cfg.timeout_s, world.name, cfg.planner)
    last_clock, last_change = -1, time.monotonic()
    with progress:
        while not monitor.done:
            watch.drain(monitor, 0.05)
            now = time.monotonic()
            if monitor.clock_ns != last_clock:
                last_clock, last_change = monitor.clock_ns, now
            progress.update(monitor.clock_ns / NS, monitor.distance_to(*world.goal[:2]),
                            monitor.batteries[-1].charge_used_mAh if monitor.batteries else 0.0,
                            monitor.status.state if monitor.status else "")
            if sup.dead():
                _on_node_death(sup, watch, monitor)
            elif now - last_change > STALL_S:
                monitor.fail(f"sim time stuck at {monitor.clock_ns / NS:.2f} s for {STALL_S:g} s "
                             "(a node is hung?)")
    _wait_for_figures(sup, watch, monitor)


def _on_node_death(sup, watch, monitor) -> None:
    """A node died: record why, and (unless it was the driver) let the robot come to a stop."""
    reason = _death_reason(sup)
    monitor.fail(reason)
    if any(c.name in ("base_driver", "router") for c in sup.dead()):
        return
    deadline = time.monotonic() + 10.0  # the driver's lockstep timeout + watchdog
    while time.monotonic() < deadline and not (monitor.watchdog_stop_ns and monitor.robot_stopped()):
        watch.drain(monitor, 0.05)
    monitor.t_end_ns = max(monitor.clock_ns, 0)


def _wait_for_figures(sup, watch, monitor, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not monitor.figures_complete() and time.monotonic() < deadline:
        if any(c.name in ("energy_meter", "base_driver") for c in sup.dead()):
            break
        watch.drain(monitor, 0.05)
    if not monitor.figures_complete():
        log.warning("figures at t_end=%.2f s incomplete (battery/pose samples missing)",
                    (monitor.t_end_ns or 0) / NS)
