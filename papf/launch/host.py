"""`papf launch PROFILE`: start this host's share of the stack, as a launch profile says.

The profile is data (:mod:`papf.launch.profile`: which nodes, their arguments, router or not,
whether this host drives a run). Supervision is :class:`papf.launch.supervisor.Supervisor`'s
(process groups, logs prefixed ``[node]``, no orphans); readiness is the nodes'
liveliness tokens; SIGINT/SIGTERM stop everything cleanly.
"""

from __future__ import annotations

import dataclasses
import re
import sys
import threading
import time

import zenoh

from common import runauth, seal
from common.errors import ConfigError, PapfError
from common.transport import StopRequested, wait_alive, zenoh_config
from nodes.planner.registry import DEFAULT_PLANNER
from papf.console.progress import RunProgress
from papf.launch import portrange
from papf.launch.claim import Claim, check_network
from papf.launch.linkwatch import LinkWatch
from papf.launch.outcome import RunMonitor, RunResult
from papf.launch.preflight import check_launch
from papf.launch.profile import LaunchOptions, Profile, load_profile, local_endpoint, resolve
from papf.launch.resume import Journal, JournalWriter, decide, drop_journal, robot_run
from papf.launch.sequence import STALL_S, RunSequence
from papf.launch.supervisor import Supervisor, free_port, port_in_use, wait_port
from schemas import Keys
from worlds import load_world


def launch(opt: LaunchOptions, stop: StopRequested | None = None,
           on_run_start=None) -> RunResult | None:
    """Start the profile's processes; drive a run if the profile says so; stop everything.

    Returns the run's result; for a serving profile (no run) None after SIGINT/SIGTERM, or
    a ``failed`` result if one of its processes died. ``on_run_start()``: called once the
    run has started (``papf run --link`` starts its link's outage schedule then).
    """
    prof = load_profile(opt.profile)
    if prof.run and "world" not in opt.values and "world" not in prof.defaults:
        raise ConfigError(f"profile {prof.name} drives a run: give --world W")
    check_launch(opt, prof)   # ConfigError/WorldError before anything starts (one preflight)
    graph = resolve(prof, opt)
    if opt.dry_run:   # the router's port as a launch would take it (--port-range, taken)
        graph = resolve(prof, free_listen(prof, opt)) if prof.router and not opt.listen else graph
        print(graph.to_json())
        return None
    keys = Keys(opt.namespace)
    with Claim(opt.namespace, prof.name, graph.nodes):   # one launch per namespace (module doc)
        if prof.router:   # a taken port: another one (said on stderr), or refused if given
            opt = free_listen(prof, opt)
            graph = resolve(prof, opt)
        joined = _joined_network(prof, opt, graph)
        if joined is not None:
            check_network(joined, keys, graph.nodes, opt.zenoh_config)
        stop = stop or StopRequested()
        show = (lambda n, line: True) if opt.verbose else (
            lambda n, line: any(k in line for k in ("WARNING", "ERROR", "Traceback", "rror:",
                                                    "ready as")))
        run_key = launch_key(prof, opt)
        run_id = seal.new_run_id() if prof.run else None
        journal = None
        if prof.run and prof.host == "laptop":   # a split: is the robot still in a run?
            run_id, journal = _run_to_join(prof, opt, graph, keys, run_key, run_id)
            if journal is not None:   # the meter goes on from the journal's account
                opt = with_meter_resume(opt, journal)
                graph = resolve(prof, opt)
        if prof.run:   # this user's `papf goal` may re-target the session (common.runauth)
            runauth.publish_key(opt.namespace, run_key, run_id or "")   # NamespaceTaken: exit 2
        try:
            return _launch(opt, prof, graph, stop, show, keys, run_key, run_id, journal,
                           on_run_start)
        finally:
            if prof.run:
                runauth.withdraw_key(opt.namespace, run_key)


def _run_to_join(prof: Profile, opt: LaunchOptions, graph, keys: Keys, run_key: str,
                 new_run: str) -> tuple[str, Journal | None]:
    """Ask the robot which run it is in, and decide by ``--resume``/``--new-run``
    (:mod:`papf.launch.resume`); ConfigError when it is in one and nothing was said."""
    try:
        with zenoh.open(_nodes_conf(prof, opt, graph.connect)) as session:
            robot = robot_run(session, keys, bytes.fromhex(run_key))
    except zenoh.ZError:
        robot = None   # no robot network yet: it has no run; the launch says why it waits
    run, journal = decide(robot, opt.after_crash, opt.namespace, new_run)
    if robot is None or not robot.running:   # nothing left behind: an ordinary new run
        opt.after_crash = "refuse"
    if journal is not None:
        print(f"papf launch {prof.name}: resuming run {run} at {robot.t_ns / 1e9:.1f} s "
              f"({journal.charge_mAh:.2f} mAh, {journal.path_m:.2f} m so far)",
              file=sys.stderr, flush=True)
    elif robot is not None and robot.running:
        print(f"papf launch {prof.name}: run {robot.run} left behind; a new run {run} from "
              "where the robot stands", file=sys.stderr, flush=True)
    return run, journal


def with_meter_resume(opt: LaunchOptions, journal: Journal) -> LaunchOptions:
    """``opt`` with the energy meter told to go on from the journal's account."""
    extra = dict(opt.extra_node_args)
    extra["energy_meter"] = [*extra.get("energy_meter", []), "--resume",
                             f"{journal.charge_mAh!r},{journal.energy_J!r},{journal.soc!r},"
                             f"{journal.battery_ns}"]
    return dataclasses.replace(opt, extra_node_args=extra)


SPLIT_HOSTS = ("robot", "laptop")   # profiles launched apart that must share a key


def launch_key(prof: Profile, opt: LaunchOptions) -> str:
    """The key this launch's processes seal with (hex). A split's two sides are launched
    apart, so they share a key made once: ``--key FILE`` (the robot side makes FILE when it is
    missing; copy it to the laptop), else this host's pairing file (robot and laptop on one
    host). Every other launch (``sim``): a fresh key of its own."""
    if prof.host not in SPLIT_HOSTS:
        return runauth.new_key()
    path = opt.key_file or runauth.pair_file(opt.namespace)
    if opt.key_file is None:
        runauth.key_file(opt.namespace).parent.mkdir(mode=0o700, exist_ok=True)
    try:
        key, made = runauth.load_pair_key(path, create=prof.host == "robot" or opt.key_file is None)
    except PapfError as exc:
        raise ConfigError(str(exc)) from None
    if made and opt.key_file is not None:
        print(f"papf launch {prof.name}: made the pairing key {path}; copy it to the other side "
              f"and give it there too (--key {path})", file=sys.stderr, flush=True)
    return key.hex()


def _nodes_conf(prof: Profile, opt: LaunchOptions, connect: list[str]) -> zenoh.Config:
    """The Zenoh config of this host's nodes and launcher (a client of ``connect``)."""
    return zenoh_config("client", connect if (opt.connect or prof.router or not opt.zenoh_config)
                        else [], config_file=opt.zenoh_config)


def _joined_network(prof: Profile, opt: LaunchOptions, graph) -> zenoh.Config | None:
    """How to reach the network of other hosts this launch's nodes will join (their router:
    ``--connect`` of a profile without a router, ``--join`` of one with), or None (a router
    of its own that joins nothing: a network of this launch alone)."""
    if not prof.router:
        return _nodes_conf(prof, opt, graph.connect)
    if opt.join:
        return zenoh_config("client", opt.join, config_file=opt.zenoh_config)
    return None


def _launch(opt: LaunchOptions, prof: Profile, graph, stop: StopRequested, show, keys: Keys,
            run_key: str, run_id: str | None, journal: Journal | None = None,
            on_run_start=None) -> RunResult | None:
    """:func:`launch` once the graph is resolved: start, wait alive, drive or serve."""
    cmds, connect = graph.nodes, graph.connect
    env = {runauth.ENV: run_key, **({seal.RUN_ID_ENV: run_id} if run_id else {})}
    with Supervisor(show=show, env=env) as sup:
        if prof.router:
            sup.start("router", list(graph.processes[0].argv))
            host, _, port = connect[0].partition("/")[2].rpartition(":")
            if connect[0].startswith("tcp/") and not wait_port(
                    int(port.split("#")[0]), 15.0, host.strip("[]"), abort=lambda: bool(sup.dead())):
                raise ConfigError(f"the router did not come up on {graph.listen}: "
                                  + " | ".join(sup.children[0].tail))
        for name, argv in cmds.items():
            sup.start(name, argv)
        with zenoh.open(_nodes_conf(prof, opt, connect)) as session:
            wanted = list(cmds) + (list(prof.remote_nodes) if prof.run else [])
            missing = wait_alive(session, keys, wanted, opt.startup_timeout_s,
                                 abort=lambda: bool(sup.dead()) or bool(stop))
            if missing or sup.dead():
                reason = "interrupted" if stop else sup.death_reason() or \
                    f"not alive after {opt.startup_timeout_s:g} s: {', '.join(sorted(missing))}"
                return _failed(reason, opt, prof)
            print(f"papf launch {prof.name}: ready ({', '.join(wanted)} alive)", file=sys.stderr,
                  flush=True)
            if prof.run:
                return _drive_run(session, keys, sup, prof, opt, stop, bytes.fromhex(run_key),
                                  run_id, journal, on_run_start)
            while not stop and not sup.dead():   # a serving host: until Ctrl-C or a death
                stop.wait(0.2)
            return _failed(sup.death_reason(), opt, prof) if sup.dead() else None


def _taken(endpoint: str) -> int | None:
    """The port of a ``tcp/HOST:PORT`` endpoint if something already listens there, else None."""
    m = re.match(r"^tcp/(.+):(\d+)$", local_endpoint(endpoint))
    if m is None or int(m.group(2)) == 0:
        return None
    port = int(m.group(2))
    return port if port_in_use(port, m.group(1).strip("[]")) else None


def free_listen(prof: Profile, opt: LaunchOptions) -> LaunchOptions:
    """The profile's router endpoints with taken TCP ports replaced by free ones (as ``papf
    run`` does); a taken port given with ``--listen`` is the user's choice: ConfigError."""
    if opt.listen:
        for ep in opt.listen:
            if _taken(ep) is not None:
                raise ConfigError(f"--listen {ep}: the port is taken (another router or papf "
                                  "launch?); stop that, or give another port (without --listen "
                                  "papf launch picks a free one)")
        return opt
    listen = []
    for ep in prof.listen:
        ep = _into_range(ep)   # --port-range: the profile's port, if outside, becomes one of it
        port = _taken(ep)
        if port is not None:
            new = re.sub(r":\d+$", f":{free_port()}", ep)
            print(f"papf launch {prof.name}: port {port} is taken (another router?); the router "
                  f"listens on {new} instead" + ("" if prof.run else
                  f" — the other host connects with --connect {new.replace('0.0.0.0', '<this-host>')}"),
                  file=sys.stderr, flush=True)
            ep = new
        listen.append(ep)
    return dataclasses.replace(opt, listen=listen) if listen != list(prof.listen) else opt


def _into_range(endpoint: str) -> str:
    """A ``tcp/HOST:PORT`` endpoint with its port moved into ``--port-range`` when outside
    it (:mod:`papf.launch.portrange`); as it is without a range."""
    rng = portrange.current()
    m = re.match(r"^(tcp/.+):(\d+)$", endpoint)
    if rng is None or m is None or int(m.group(2)) in rng:
        return endpoint
    return f"{m.group(1)}:{portrange.free_in_range(rng, lowest=True)}"


def _failed(reason: str, opt: LaunchOptions, prof: Profile) -> RunResult:
    print(f"papf launch {prof.name}: {reason}", file=sys.stderr)
    monitor = RunMonitor(opt.timeout_s)
    monitor.fail(reason)
    return _result(monitor, opt, prof)


def _result(monitor: RunMonitor, opt: LaunchOptions, prof: Profile, wall_s: float = 0.0):
    world = opt.values.get("world") or prof.defaults.get("world", "")
    return monitor.result(str(opt.values.get("planner") or prof.defaults.get("planner", DEFAULT_PLANNER)),
                          load_world(world).name if world else "", int(opt.values.get("seed") or 0),
                          wall_s)


# -- the run sequence (docs/architecture.md "Start and end of a run", real time) ---------------
ROBOT_QUIET_S = 1.0   # [s wall] without the robot's odometry before the launcher says it waits


def _robot_talks(session, keys: Keys, prof: Profile, opt: LaunchOptions, sup: Supervisor,
                 stop: StopRequested, key: bytes) -> str:
    """Wait (at most ``--startup-timeout``) until the base driver publishes the robot's
    odometry (it does, at 10 Hz between runs, once the robot's own reaches it): the run's
    clock and timeout must not start on a robot that is not talking yet. Says so on stderr
    after :data:`ROBOT_QUIET_S`. "" once it talks with this launch's seal; else why not (a
    timeout, a stop, a death, or a robot side sealing with another key or none)."""
    heard, sealed = threading.Event(), threading.Event()
    opener = seal.Opener(key, None)

    def on_odom(sample) -> None:   # Zenoh's thread: note it, and whether its seal is ours
        att = sample.attachment
        verdict, _ = opener.check(keys.odom, sample.payload.to_bytes(),
                                  None if att is None else att.to_bytes())
        (sealed if verdict == seal.OK else heard).set()

    sub = session.declare_subscriber(keys.odom, on_odom)
    try:
        if not (sealed.wait(ROBOT_QUIET_S) or heard.is_set()):
            print(f"papf launch {prof.name}: waiting for the robot's odometry on {keys.odom} "
                  "(the base driver has none from the robot yet: bringup and bridge up?)",
                  file=sys.stderr, flush=True)
        deadline = time.monotonic() + opt.startup_timeout_s
        while not sealed.wait(0.2):
            if stop or sup.dead() or time.monotonic() > deadline:
                return _silent_robot(opt, sup, stop)
            if heard.is_set() and time.monotonic() > deadline - opt.startup_timeout_s + PAIR_S:
                return (f"the robot side's odometry on {keys.odom} is not sealed with this "
                        "launch's key: give both sides the same key file (papf launch robot "
                        "--key F, then papf launch laptop --key F; docs/robot.md \"Pairing\")")
        return ""
    finally:
        sub.undeclare()


PAIR_S = 3.0   # [s wall] the robot's odometry heard but never with our seal: another key


def _silent_robot(opt: LaunchOptions, sup: Supervisor, stop: StopRequested) -> str:
    return "interrupted" if stop else sup.death_reason() or (
        f"no odometry from the robot within {opt.startup_timeout_s:g} s: the base "
        "driver gets none over its bridge (start the robot's bringup and "
        "zenoh-bridge-ros2dds, or rmw_zenoh; docs/getting-started-robot.md)")


def _drive_run(session, keys: Keys, sup: Supervisor, prof: Profile, opt: LaunchOptions,
               stop: StopRequested, run_key: bytes, run_id: str,
               journal: Journal | None = None, on_run_start=None) -> RunResult:
    wall0 = time.monotonic()
    world = load_world(opt.values.get("world") or prof.defaults["world"])
    goal = journal.goal if journal is not None else (world.goal[0], world.goal[1], world.tolerance)
    monitor = RunMonitor(opt.timeout_s, goal=goal)
    if journal is not None:   # the same run: path and first motion go on from the journal
        monitor.resume(journal.path_m, journal.motion_start_ns,
                       None if journal.x is None else (journal.x, journal.y))
        world = dataclasses.replace(world, goal=goal[:2], tolerance=goal[2])
    why = _robot_talks(session, keys, prof, opt, sup, stop, run_key) \
        if prof.pose_topic == "odom" else ""
    if why:
        monitor.fail(why)
        return _result(monitor, opt, prof, time.monotonic() - wall0)
    link = LinkWatch() if prof.remote_nodes else None   # a split: the link is watched
    seq = RunSequence(session, keys, sup, monitor, prof.pose_topic, stop=lambda: bool(stop),
                      stall_s=opt.stall_s or STALL_S, run_key=run_key, run_id=bytes.fromhex(run_id),
                      link=link)
    if prof.host == "laptop":   # a crash of this laptop can be resumed from it
        writer = JournalWriter(opt.namespace, journal or Journal(run_id, world.name, goal))
        seq.watchers.append(writer.update)
    planner = str(opt.values.get("planner") or prof.defaults.get("planner", DEFAULT_PLANNER))
    try:
        if seq.handshake(world):
            if journal is None:   # resumed: the robot's clock goes on, no new start
                seq.start(f"profile={prof.name} world={world.name}"
                          + (" frame=keep" if opt.after_crash == "new" else ""))
            if on_run_start is not None:
                on_run_start()
            with RunProgress(None, opt.timeout_s, world.name, planner) as progress:
                seq.until_outcome(progress, world.goal[:2])
    finally:
        result = _result(monitor, opt, prof, time.monotonic() - wall0)
        if link is not None:
            _judge_link(result, link)
        seq.end(result)
        drop_journal(opt.namespace, run_id)
    return result


def _judge_link(result: RunResult, link: LinkWatch) -> None:
    """The run's ``link`` figures, and its reason when the link ended it."""
    now = time.monotonic_ns()
    result.link = link.summary(now)
    blamed = link.blame(result.outcome, result.reason, now, result.sim_time_s)
    if blamed:
        result.reason = blamed


