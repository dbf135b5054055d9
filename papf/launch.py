"""`papf launch PROFILE`: start this host's share of the stack, as a launch profile says.

The profile is data (:mod:`papf.graph`: which nodes, their arguments, router or not,
whether this host drives a run). Supervision is :class:`papf.supervisor.Supervisor`'s
(process groups, logs prefixed ``[node]``, no orphans); readiness is the nodes'
liveliness tokens; SIGINT/SIGTERM stop everything cleanly.
"""

from __future__ import annotations

import sys
import time

import zenoh

from common.errors import ConfigError
from common.transport import StopRequested, wait_alive, zenoh_config
from papf.graph import LaunchOptions, Profile, load_profile, resolve
from papf.monitor import RunMonitor, RunResult
from papf.run_sequence import STALL_S, RunSequence
from papf.supervisor import Supervisor, wait_port
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
    graph = resolve(prof, opt)
    if opt.dry_run:
        print(graph.to_json())
        return None
    cmds, connect = graph.nodes, graph.connect
    stop = stop or StopRequested()
    show = (lambda n, line: True) if opt.verbose else (
        lambda n, line: any(k in line for k in ("WARNING", "ERROR", "Traceback", "rror:", "ready as")))
    keys = Keys(opt.namespace)
    with Supervisor(show=show) as sup:
        if prof.router:
            sup.start("router", list(graph.processes[0].argv))
            host, _, port = connect[0].partition("/")[2].rpartition(":")
            if connect[0].startswith("tcp/") and not wait_port(
                    int(port.split("#")[0]), 15.0, host.strip("[]"), abort=lambda: bool(sup.dead())):
                raise ConfigError(f"the router did not come up on {graph.listen}: "
                                  + " | ".join(sup.children[0].tail))
        for name, argv in cmds.items():
            sup.start(name, argv)
        conf = zenoh_config("client", connect if (opt.connect or prof.router or not opt.zenoh_config)
                            else [], config_file=opt.zenoh_config)
        with zenoh.open(conf) as session:
            wanted = list(cmds) + (list(prof.remote_nodes) if prof.run else [])
            missing = wait_alive(session, keys, wanted, opt.startup_timeout_s,
                                 abort=lambda: bool(sup.dead()) or bool(stop))
            if missing or sup.dead():
                reason = sup.death_reason() or f"not alive after {opt.startup_timeout_s:g} s: " \
                                        f"{', '.join(sorted(missing))}"
                return _failed(reason, opt, prof)
            print(f"papf launch {prof.name}: ready ({', '.join(wanted)} alive)", file=sys.stderr,
                  flush=True)
            if prof.run:
                return _drive_run(session, keys, sup, prof, opt, stop)
            while not stop and not sup.dead():   # a serving host: until Ctrl-C or a death
                stop.event.wait(0.2)
            return _failed(sup.death_reason(), opt, prof) if sup.dead() else None


def _failed(reason: str, opt: LaunchOptions, prof: Profile) -> RunResult:
    print(f"papf launch {prof.name}: {reason}", file=sys.stderr)
    monitor = RunMonitor(opt.timeout_s)
    monitor.fail(reason)
    return _result(monitor, opt, prof)


def _result(monitor: RunMonitor, opt: LaunchOptions, prof: Profile, wall_s: float = 0.0):
    world = opt.values.get("world") or prof.defaults.get("world", "")
    return monitor.result(str(opt.values.get("planner") or prof.defaults.get("planner", "apf")),
                          load_world(world).name if world else "", int(opt.values.get("seed") or 0),
                          wall_s)


# -- the run sequence (docs/architecture.md "Start and end of a run", real time) ---------------
def _drive_run(session, keys: Keys, sup: Supervisor, prof: Profile, opt: LaunchOptions,
               stop: StopRequested) -> RunResult:
    wall0 = time.monotonic()
    world = load_world(opt.values.get("world") or prof.defaults["world"])
    monitor = RunMonitor(opt.timeout_s)
    seq = RunSequence(session, keys, sup, monitor, prof.pose_topic, stop=lambda: bool(stop),
                      stall_s=opt.stall_s or STALL_S)
    try:
        if seq.handshake(world):
            seq.start(f"profile={prof.name} world={world.name}")
            seq.until_outcome()
    finally:
        result = _result(monitor, opt, prof, time.monotonic() - wall0)
        seq.end(result)
    return result


