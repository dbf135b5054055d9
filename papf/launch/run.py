"""`papf run`: start the whole stack as processes, drive to an outcome, stop everything.

The processes are the ``sim`` launch profile's (:mod:`papf.launch.profile`; ``papf launch sim``
starts the same list), but the router is the launcher's own Zenoh session (no router
process). Sequence (docs/architecture.md): router -> nodes -> liveliness -> then
:class:`papf.launch.sequence.RunSequence` (goal handshake -> run_started -> outcome ->
figures at ``t_end`` -> run_ended) -> stop the nodes, the recorder, the router.
"""

from __future__ import annotations

import logging
import sys
import time
from dataclasses import dataclass, field, replace

import zenoh

from common import runauth, seal
from common.drive import DRIVER_OPTIONS
from common.errors import ConfigError
from common.params import check_value
from common.transport import wait_alive, zenoh_config
from common.units import LOCKSTEP_TIMEOUT_S, pair_timeout_s
from nodes.energy_meter.models import DEFAULT_MODEL
from nodes.planner.registry import DEFAULT_PLANNER
from papf.console.progress import RunProgress
from papf.launch import portrange
from papf.launch.fleet import FleetMeter, fleet_result, progress_figures
from papf.launch.outcome import RunMonitor, RunResult
from papf.launch.preflight import bag_path, check_run
from papf.launch.profile import LaunchOptions, Resolved, load_profile, resolve
from papf.launch.sequence import CHECK_S, COALESCE_S, STALL_S, RunSequence
from papf.launch.supervisor import Supervisor, free_port, port_in_use
from schemas import Keys, People
from worlds import World, load_world

log = logging.getLogger("papf.run")

DEFAULT_PORT = 7447
PROFILE = "sim"   # papf run = this launch profile + the run sequence


@dataclass
class RunConfig:
    world: str
    planner: str = DEFAULT_PLANNER
    seed: int = 0
    timeout_s: float = 300.0           # [s sim time]
    realtime: bool = False
    record: str | None = None
    force: bool = False                # replace an existing recording
    port: int | None = None            # None: 7447, or a free port if 7447 is taken
    namespace: str = "rosbot"
    planner_args: list[str] = field(default_factory=list)   # e.g. ["--set", "v_max=0.3"]
    energy_model: str = DEFAULT_MODEL
    stop_on_collision: bool = True
    verbose: bool = False
    progress: bool | None = None       # None: when stderr is a terminal
    startup_timeout_s: float = 60.0    # [s wall] for every node to become alive
    lockstep_timeout_s: float = LOCKSTEP_TIMEOUT_S   # [s wall] driver waits this long for a command
    extra_node_args: dict[str, list[str]] = field(default_factory=dict)
    zenoh_mode: str = "peer"           # nodes' Zenoh mode: peer (direct links, default) or client
    view: int | None = None            # serve a Foxglove view on this port (docs/viewer.md)
    ros_face: int | None = None        # the ROS 2 face's domain (nodes.ros_face); None: off
    ros_face_distro: str | None = None  # the face's ROS 2 distro (jazzy, humble); None: jazzy
    record_format: str = "mcap"        # --record as mcap (ours) or ros2 (a rosbag2 directory)
    objects: str | None = None         # none | truth | tracker; None: per planner (graph.objects_for)
    link: str | None = None            # papf run --link PROFILE|SPEC (papf.launch.split)
    robot_trace: str | None = None     # --link: the emulated robot's command trace (JSON lines)
    robot_record: str | None = None    # --link: the robot side's own recording (its black box)
    passing: str | None = None         # a fleet's: orca | off; None: orca (profile._passing)
    odom_hz: float | None = None       # the sim's odometry tick; None: 50, a fleet's the scan rate


def launch_options(cfg: RunConfig, port: int) -> LaunchOptions:
    """The ``sim`` profile's options for this run (``papf launch sim`` takes the same)."""
    values = {"world": cfg.world, "planner": cfg.planner, "seed": cfg.seed,
              "energy_model": cfg.energy_model, "record": cfg.record,
              "record_force": "1" if cfg.force and cfg.record else None,
              "record_format": "ros2" if cfg.record and cfg.record_format == "ros2" else None,
              "lockstep_timeout": f"{cfg.lockstep_timeout_s:g}",
              "pair_timeout": (None if cfg.lockstep_timeout_s == LOCKSTEP_TIMEOUT_S   # the
                               else f"{pair_timeout_s(cfg.lockstep_timeout_s):g}"),   # nodes' own
              "realtime": "1" if cfg.realtime else None,
              "objects": cfg.objects, "view": cfg.view, "passing": cfg.passing,
              "odom_hz": None if cfg.odom_hz is None else f"{cfg.odom_hz:g}",
              "ros_face": None if cfg.ros_face is None else "1",
              "ros_face_domain": cfg.ros_face,
              "ros_face_distro": cfg.ros_face_distro if cfg.ros_face is not None else None}
    return LaunchOptions(PROFILE, listen=[f"tcp/127.0.0.1:{port}"], namespace=cfg.namespace,
                         values={k: v for k, v in values.items() if v is not None},
                         planner_args=list(cfg.planner_args), timeout_s=cfg.timeout_s,
                         zenoh_mode=cfg.zenoh_mode, extra_node_args=cfg.extra_node_args,
                         startup_timeout_s=cfg.startup_timeout_s, verbose=cfg.verbose)


def resolve_run(cfg: RunConfig, port: int | None = None) -> Resolved:
    """The processes of this run: the ``sim`` profile resolved with its options."""
    return resolve(load_profile(PROFILE), launch_options(cfg, port or router_port(cfg.port)))


ROUTER_TRIES = 3   # a router port taken between its choice and the listen: choose again


def router_port(port: int | None) -> int:
    """``--port``; else 7447 when it is free and inside ``--port-range`` (if one is set),
    else a free port (of the range: :mod:`papf.launch.portrange`)."""
    if port:
        return port
    rng = portrange.current()
    if (rng is None or DEFAULT_PORT in rng) and not port_in_use(DEFAULT_PORT):
        return DEFAULT_PORT
    return free_port() if rng is None else portrange.free_in_range(rng, lowest=True)


def _show_line(verbose: bool):
    keys = ("WARNING", "ERROR", "CRITICAL", "Traceback", "Error", "error:")
    return lambda name, line: verbose or any(k in line for k in keys)


def preflight(cfg: RunConfig) -> World:
    """The world, once every option passed the one preflight (exit 2 otherwise): what
    ``papf run`` checks before it starts anything — and ``--dry-run`` too, so a dry run never
    prints a process list that the real run would refuse."""
    world = load_world(cfg.world)  # WorldError before anything starts
    bag = cfg.record is not None and cfg.record_format == "ros2"
    if bag:   # a rosbag2 directory, checked as such (preflight.record_path checks files)
        bag_path(cfg.record, cfg.force)
    check_run(world, cfg.planner, cfg.seed, cfg.timeout_s, cfg.port, cfg.namespace,
              None if bag else cfg.record, cfg.planner_args, force=cfg.force,
              view=cfg.view)
    check_value("--lockstep-timeout", cfg.lockstep_timeout_s, DRIVER_OPTIONS["lockstep_timeout"])
    if cfg.realtime and cfg.lockstep_timeout_s != LOCKSTEP_TIMEOUT_S:
        raise ConfigError("--lockstep-timeout: a lockstep run's; with --realtime the simulator "
                          "goes at the wall clock's pace and never waits for a command: drop one")
    if cfg.odom_hz is not None:   # on the physics step's grid, the scans on its own
        from nodes.world_sim.core import WorldConfig  # pybullet: only when asked

        WorldConfig.from_rates(cfg.odom_hz)
    return world


def run(cfg: RunConfig) -> RunResult:
    """Run the whole stack once; always stops every process it started."""
    world = preflight(cfg)   # before anything starts
    wall0 = time.monotonic()
    monitor = RunMonitor(cfg.timeout_s, cfg.stop_on_collision,
                         goal=(world.goal[0], world.goal[1], world.tolerance))
    keys = Keys(cfg.namespace)
    run_key = runauth.new_key()    # to the nodes through their environment only
    run_id = seal.new_run_id()     # every sample of this run carries it (common.seal)
    # this user's `papf goal` may steer a real-time run (common.runauth); a lockstep run stays
    # reproducible. Claimed before the router opens: a namespace another launch of this user
    # holds is a usage error (NamespaceTaken, exit 2) before anything starts
    if cfg.realtime:
        runauth.publish_key(cfg.namespace, run_key, run_id)
    try:
        router, graph, why = open_router(cfg)
        if router is None:
            monitor.fail(why)
            return monitor.result(cfg.planner, world.name, cfg.seed, time.monotonic() - wall0)
        return _run(cfg, world, graph, router, run_key, run_id, monitor, keys, wall0)
    finally:
        if cfg.realtime:
            runauth.withdraw_key(cfg.namespace, run_key)


def open_router(cfg: RunConfig, tries: int = ROUTER_TRIES) -> tuple[zenoh.Session | None, Resolved, str]:
    """The embedded router, the run's processes around its port, and "" — or None, the
    processes and why it could not listen.

    The launcher's own session is the embedded router (a Python process, as the profile
    says, but this one): no router process to start and wait for, and the launcher's
    subscriptions are served without a hop. The nodes are stopped before it closes. A port
    someone else listens on (another stack's router) fails here: nothing published. Without
    ``--port``, a port taken between its choice and the listen (two runs started at once:
    both saw 7447 free) is chosen again, up to ``tries`` times."""
    for attempt in range(1, max(tries, 1) + 1):
        port = router_port(cfg.port)
        if cfg.port is None and port != DEFAULT_PORT and port_in_use(DEFAULT_PORT):
            log.warning("port %d is in use; the embedded router listens on %d instead",
                        DEFAULT_PORT, port)
        graph = resolve_run(cfg, port)
        try:   # no multicast, nothing to connect to: no scouting delay (Zenoh's default 0.5 s)
            return zenoh.open(zenoh_config("router", listen=[f"tcp/127.0.0.1:{port}"],
                                           scout_delay_ms=0)), graph, ""
        except Exception as exc:  # zenoh raises ZError (e.g. the port was taken meanwhile)
            why = f"the embedded router could not listen on {graph.connect[0]}: {exc}"
            if cfg.port is not None or attempt >= tries:
                return None, graph, why
            log.warning("port %d was taken as the router started; choosing another", port)
    raise AssertionError("the last try returns")


def _run(cfg: RunConfig, world: World, graph: Resolved, router: zenoh.Session, run_key: str,
         run_id: str, monitor: RunMonitor, keys: Keys, wall0: float) -> RunResult:
    """:func:`run` once its router is open: start the nodes, drive the run, stop them."""
    if world.robots or world.has_people:
        return _run_fleet(cfg, world, graph, router, run_key, run_id, wall0)
    with router as session, Supervisor(show=_show_line(cfg.verbose), last=("recorder",),
                                       env={runauth.ENV: run_key, seal.RUN_ID_ENV: run_id}) as sup:
        seq = RunSequence(session, keys, sup, monitor, stall_s=stall_s(cfg),
                          run_key=bytes.fromhex(run_key), run_id=bytes.fromhex(run_id))
        try:
            _drive(cfg, world, graph.nodes, sup, session, keys, seq)
        finally:
            result = monitor.result(cfg.planner, world.name, cfg.seed, time.monotonic() - wall0)
            seq.end(result)  # before the nodes stop: the recorder keeps the result
    result.wall_time_s = time.monotonic() - wall0
    return result


def _run_fleet(cfg: RunConfig, world: World, graph: Resolved, router: zenoh.Session,
               run_key: str, run_id: str, wall0: float) -> RunResult:
    """:func:`_run` for a fleet (``[[robots]]``): a sequence per robot namespace, one result
    (:mod:`papf.launch.fleet`)."""
    robots = [replace(r, name=r.name or cfg.namespace) for r in world.fleet]
    names = [r.name for r in robots]
    planners = {r.name: r.planner or cfg.planner for r in robots}
    goals = {r.name: tuple(r.goal) for r in robots}
    meter = FleetMeter(names, goals, world.has_people,
                       groups=tuple(g.members for g in world.groups))
    with router as session, Supervisor(show=_show_line(cfg.verbose), last=("recorder",),
                                       env={runauth.ENV: run_key, seal.RUN_ID_ENV: run_id}) as sup:
        seqs = {}
        for r in robots:
            monitor = RunMonitor(cfg.timeout_s, cfg.stop_on_collision,
                                 goal=(r.goal[0], r.goal[1], r.tolerance))
            seqs[r.name] = seq = RunSequence(session, Keys(r.name), sup, monitor,
                                             run_key=bytes.fromhex(run_key),
                                             run_id=bytes.fromhex(run_id), commands=False)
            seq.watch_poses(lambda msg, n=r.name: meter.on_pose(n, msg))
        if world.has_people:   # on the driver's namespace, the run's
            seqs[names[0]].watch_key(Keys(cfg.namespace).key("sim/people"), People,
                                     meter.on_people)
        try:
            _drive_fleet(cfg, world, robots, graph.nodes, sup, session, seqs, goals)
        finally:
            result = fleet_result([(n, planners[n], seqs[n].monitor) for n in names], meter,
                                  world.name, cfg.seed, time.monotonic() - wall0)
            end_ns = max(seqs[n].monitor.t_end_ns or max(seqs[n].monitor.clock_ns, 0)
                         for n in names)
            for n in names[1:]:   # the recorder watches the first robot's events: last
                seqs[n].end(result, wait_recorder=False, stamp_ns=end_ns)
            seqs[names[0]].end(result, stamp_ns=end_ns)
    result.wall_time_s = time.monotonic() - wall0
    return result


def _alive_groups(commands: dict[str, list[str]]) -> dict[str, list[str]]:
    """Liveliness names per namespace: each process's ``--namespace``, its name's last part;
    a process serving several robots (``--robots r1,r2``) in each of theirs too."""
    groups: dict[str, list[str]] = {}
    for name, argv in commands.items():
        node = name.rpartition("/")[2]
        ns = argv[len(argv) - 1 - argv[::-1].index("--namespace") + 1]
        served = argv[argv.index("--robots") + 1].split(",") if "--robots" in argv else []
        for n in (ns, *served):
            groups.setdefault(n, []).append(node)
    return groups


def _wait_fleet_alive(cfg: RunConfig, commands: dict[str, list[str]], sup: Supervisor,
                      session: zenoh.Session, robots: list[str]) -> str:
    """Wait for every process's token in its namespace (and the driver's in each robot's);
    the reason if one never came or a process died, else ""."""
    groups = _alive_groups(commands)
    for n in robots:   # the driver's share of each robot
        if "base_driver" not in groups.setdefault(n, []):
            groups[n].append("base_driver")
    for ns, names in groups.items():
        missing = wait_alive(session, Keys(ns), names, cfg.startup_timeout_s,
                             abort=lambda: bool(sup.dead()))
        if missing or sup.dead():
            return sup.death_reason() or (f"nodes not alive after {cfg.startup_timeout_s:g} s: "
                                          + ", ".join(f"{ns}/{m}" for m in sorted(missing)))
    return ""


def _drive_fleet(cfg: RunConfig, world: World, robots: list, commands: dict[str, list[str]],
                 sup: Supervisor, session: zenoh.Session, seqs: dict[str, RunSequence],
                 goals: dict[str, tuple[float, float]]) -> None:
    monitors = {n: s.monitor for n, s in seqs.items()}
    for name, argv in commands.items():
        sup.start(name, argv)
    reason = _wait_fleet_alive(cfg, commands, sup, session, list(seqs))
    if reason:
        for m in monitors.values():
            m.fail(reason)
        return
    if cfg.view is not None:
        print(view_line(cfg.view, cfg.realtime), file=sys.stderr, flush=True)
    for n, seq in seqs.items():
        goal = next(r for r in robots if r.name == n)
        if not seq.handshake(replace(world, goal=goal.goal, tolerance=goal.tolerance)):
            for m in monitors.values():
                if not m.done:
                    m.fail(seq.monitor.reason)
            return
    for seq in seqs.values():
        seq.start(f"world={world.name} planner={cfg.planner} seed={cfg.seed} robots={len(seqs)}")
    with RunProgress(cfg.progress, cfg.timeout_s, world.name,
                     f"{len(seqs)} robots") as progress:
        watch_fleet(seqs, sup, progress, goals, stall_s(cfg))


def stall_s(cfg: RunConfig) -> float:
    """[s wall] how long the launcher waits for the sim clock to move before it calls the
    stack stuck: :data:`~papf.launch.sequence.STALL_S`, or twice a longer lockstep timeout
    (the simulator's whole wait for a command, and as long again)."""
    return max(STALL_S, 2.0 * cfg.lockstep_timeout_s)


def watch_fleet(seqs: dict[str, RunSequence], sup: Supervisor, progress,
                goals: dict[str, tuple[float, float]], stall: float = STALL_S) -> None:
    """Until every robot has an outcome: drain each robot's messages; a dead node, a stall
    or a stop ends every robot still running; then the figures at each robot's ``t_end``."""
    monitors = {n: s.monitor for n, s in seqs.items()}
    last_clock, last_change, next_check = -1, time.monotonic(), 0.0
    while not all(m.done for m in monitors.values()):
        for seq in seqs.values():
            seq.drain(0.0)
        time.sleep(COALESCE_S)   # found or not: the next messages gather, one wake per batch
        now = time.monotonic()
        if now < next_check:
            continue
        next_check = now + CHECK_S
        clock = min(m.clock_ns for m in monitors.values())
        if clock != last_clock:
            last_clock, last_change = clock, now
        if progress is not None:
            progress.update(*progress_figures(monitors, goals))
        reason = sup.death_reason() if sup.dead() else (
            f"sim time stuck at {clock / 1e9:.2f} s for {stall:g} s"
            if now - last_change > stall else "")
        if reason:
            for m in monitors.values():
                if not m.done:
                    m.fail(reason)
    for seq in seqs.values():
        seq.wait_for_figures()


def view_line(port: int, realtime: bool) -> str:
    """Where the live view is, printed once every node (the viewer too) is alive."""
    pace = ("" if realtime else "; without --realtime the run goes as fast as the nodes "
            "compute, add --realtime to watch it at the robot's pace")
    return (f"papf run: live view on ws://127.0.0.1:{port} (Foxglove: Open connection, "
            f"docs/foxglove-layout.json){pace}")


def _drive(cfg: RunConfig, world: World, commands: dict[str, list[str]], sup: Supervisor,
           session: zenoh.Session, keys: Keys, seq: RunSequence) -> None:
    for name, argv in commands.items():
        sup.start(name, argv)
    missing = wait_alive(session, keys, commands, cfg.startup_timeout_s,
                         abort=lambda: bool(sup.dead()))
    if missing or sup.dead():
        seq.monitor.fail(sup.death_reason() or f"nodes not alive after "
                         f"{cfg.startup_timeout_s:g} s: {', '.join(sorted(missing))}")
        return
    if cfg.view is not None:
        print(view_line(cfg.view, cfg.realtime), file=sys.stderr, flush=True)
    if not seq.handshake(world):
        return
    seq.start(f"world={world.name} planner={cfg.planner} seed={cfg.seed}")
    with RunProgress(cfg.progress, cfg.timeout_s, world.name, cfg.planner) as progress:
        seq.until_outcome(progress, world.goal[:2])
