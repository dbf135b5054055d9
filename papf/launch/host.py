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

from common import runauth
from common.errors import ConfigError
from common.transport import StopRequested, wait_alive, zenoh_config
from nodes.planner.registry import DEFAULT_PLANNER
from papf.console.progress import RunProgress
from papf.launch import portrange
from papf.launch.claim import Claim, check_network
from papf.launch.outcome import RunMonitor, RunResult
from papf.launch.preflight import check_launch
from papf.launch.profile import LaunchOptions, Profile, load_profile, local_endpoint, resolve
from papf.launch.sequence import STALL_S, RunSequence
from papf.launch.supervisor import Supervisor, free_port, port_in_use, wait_port
from schemas import Keys
from worlds import load_world


def launch(opt: LaunchOptions, stop: StopRequested | None = None) -> RunResult | None:
    """Start the profile's processes; drive a run if the profile says so; stop everything.

    Returns the run's result; for a serving profile (no run) None after SIGINT/SIGTERM, or
    a ``failed`` result if one of its processes died.
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
        run_key = runauth.new_key() if prof.run else None
        if run_key:   # this user's `papf goal` may re-target the session (common.runauth)
            try:
                runauth.publish_key(opt.namespace, run_key)
            except runauth.NamespaceTaken as exc:
                raise ConfigError(str(exc)) from None
        try:
            return _launch(opt, prof, graph, stop, show, keys, run_key)
        finally:
            if run_key:
                runauth.withdraw_key(opt.namespace, run_key)


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
            run_key: str | None) -> RunResult | None:
    """:func:`launch` once the graph is resolved: start, wait alive, drive or serve."""
    cmds, connect = graph.nodes, graph.connect
    with Supervisor(show=show, env={runauth.ENV: run_key} if run_key else None) as sup:
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
                reason = sup.death_reason() or f"not alive after {opt.startup_timeout_s:g} s: " \
                                        f"{', '.join(sorted(missing))}"
                return _failed(reason, opt, prof)
            print(f"papf launch {prof.name}: ready ({', '.join(wanted)} alive)", file=sys.stderr,
                  flush=True)
            if prof.run:   # the goal is signed only for a planner this launcher started
                key = bytes.fromhex(run_key) if "planner" in cmds else None
                return _drive_run(session, keys, sup, prof, opt, stop, key)
            while not stop and not sup.dead():   # a serving host: until Ctrl-C or a death
                stop.event.wait(0.2)
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
                 stop: StopRequested) -> bool:
    """Wait (at most ``--startup-timeout``) until the base driver publishes the robot's
    odometry (it does, at 10 Hz between runs, once the robot's own reaches it): the run's
    clock and timeout must not start on a robot that is not talking yet. Says so on stderr
    after :data:`ROBOT_QUIET_S`. False on a timeout, a stop or a death."""
    heard = threading.Event()
    sub = session.declare_subscriber(keys.odom, lambda _sample: heard.set())
    try:
        if heard.wait(ROBOT_QUIET_S):
            return True
        print(f"papf launch {prof.name}: waiting for the robot's odometry on {keys.odom} (the "
              "base driver has none from the robot yet: bringup and bridge up?)",
              file=sys.stderr, flush=True)
        deadline = time.monotonic() + opt.startup_timeout_s
        while not heard.wait(0.2):
            if stop or sup.dead() or time.monotonic() > deadline:
                return False
        return True
    finally:
        sub.undeclare()
def _drive_run(session, keys: Keys, sup: Supervisor, prof: Profile, opt: LaunchOptions,
               stop: StopRequested, run_key: bytes | None = None) -> RunResult:
    wall0 = time.monotonic()
    world = load_world(opt.values.get("world") or prof.defaults["world"])
    monitor = RunMonitor(opt.timeout_s, goal=(world.goal[0], world.goal[1], world.tolerance))
    if prof.pose_topic == "odom" and not _robot_talks(session, keys, prof, opt, sup, stop):
        monitor.fail("interrupted" if stop else sup.death_reason() or
                     f"no odometry from the robot within {opt.startup_timeout_s:g} s: the base "
                     "driver gets none over its bridge (start the robot's bringup and "
                     "zenoh-bridge-ros2dds, or rmw_zenoh; docs/getting-started-robot.md)")
        return _result(monitor, opt, prof, time.monotonic() - wall0)
    seq = RunSequence(session, keys, sup, monitor, prof.pose_topic, stop=lambda: bool(stop),
                      stall_s=opt.stall_s or STALL_S, run_key=run_key)
    planner = str(opt.values.get("planner") or prof.defaults.get("planner", DEFAULT_PLANNER))
    try:
        if seq.handshake(world):
            seq.start(f"profile={prof.name} world={world.name}")
            with RunProgress(None, opt.timeout_s, world.name, planner) as progress:
                seq.until_outcome(progress, world.goal[:2])
    finally:
        result = _result(monitor, opt, prof, time.monotonic() - wall0)
        seq.end(result)
    return result


