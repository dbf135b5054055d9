"""`papf launch PROFILE`: start this host's share of the stack, as a TOML profile says.

A profile (``papf/profiles/<name>.toml``, or any path) names the nodes that run on this
host and their arguments, whether this host runs the Zenoh router, and whether it drives
a run (goal handshake, ``run_started``, outcome) — see docs/robot.md for the format and
the packaged ``sim``, ``robot``, ``laptop``, ``hil-robot`` and ``hil-laptop``. Supervision
is :class:`papf.supervisor.Supervisor`'s (process groups, logs prefixed ``[node]``, no
orphans); readiness is the nodes' liveliness tokens; SIGINT/SIGTERM stop everything cleanly.
"""

from __future__ import annotations

import re
import shlex
import sys
import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import zenoh

from common.errors import ConfigError
from common.transport import StopRequested, wait_alive, zenoh_config
from papf.monitor import RunMonitor, RunResult
from papf.run_sequence import STALL_S, RunSequence
from papf.supervisor import Supervisor, wait_port
from papf.viewer_cli import viewer_argv
from schemas import Keys
from schemas.keys import TOPICS
from worlds import load_world, world_path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

VARIABLES = ("world", "world_file", "seed", "planner", "record", "energy_model", "bridge_namespace")


@dataclass(frozen=True)
class NodeSpec:
    name: str                               # liveliness name (``<ns>/alive/<name>``)
    module: str                             # ``python -m <module>``
    args: tuple[str, ...] = ()              # may use {variables}
    needs: str | None = None                # start only when this variable is set
    if_set: dict = field(default_factory=dict)   # variable -> extra args when it is set


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    nodes: tuple[NodeSpec, ...]
    router: bool = False                    # run the embedded router on this host
    listen: tuple[str, ...] = ()            # the router's endpoints
    connect: tuple[str, ...] = ()           # where this host's nodes connect (no router here)
    run: bool = False                       # drive a run from this host
    remote_nodes: tuple[str, ...] = ()      # nodes on the other host that a run waits for
    pose_topic: str = "odom"                # pose samples of the run summary
    defaults: dict = field(default_factory=dict)


def packaged_profiles() -> list[str]:
    root = resources.files("papf") / "profiles"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def load_profile(name_or_path: str) -> Profile:
    """A packaged profile by name, or a TOML file by path; ConfigError says what is wrong."""
    path = Path(name_or_path)
    if not (path.suffix == ".toml" or "/" in name_or_path):
        path = Path(str(resources.files("papf") / "profiles" / f"{name_or_path}.toml"))
    if not path.is_file():
        raise ConfigError(f"no launch profile {name_or_path!r}; packaged: "
                          f"{', '.join(packaged_profiles())} (or a path to a .toml file)")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        nodes = tuple(NodeSpec(n["name"], n["module"], tuple(n.get("args", ())), n.get("needs"),
                               dict(n.get("if_set", {}))) for n in data.get("nodes", ()))
        prof = Profile(data.get("name", path.stem), data.get("description", ""), nodes,
                       bool(data.get("router", False)), tuple(data.get("listen", ())),
                       tuple(data.get("connect", ())), bool(data.get("run", False)),
                       tuple(data.get("remote_nodes", ())), data.get("pose_topic", "odom"),
                       dict(data.get("defaults", {})))
    except (tomllib.TOMLDecodeError, KeyError, TypeError, AttributeError) as exc:
        raise ConfigError(f"launch profile {str(path)!r} is invalid: {type(exc).__name__}: "
                          f"{exc} (see docs/robot.md for the format)") from None
    if prof.pose_topic not in TOPICS:
        raise ConfigError(f"profile {prof.name}: pose_topic {prof.pose_topic!r} is not one of "
                          f"{sorted(TOPICS)}")
    if prof.router and not prof.listen:
        raise ConfigError(f"profile {prof.name}: router = true needs listen endpoints")
    return prof


@dataclass
class LaunchOptions:
    profile: str
    connect: list[str] = field(default_factory=list)
    listen: list[str] = field(default_factory=list)
    namespace: str = "rosbot"
    zenoh_config: str | None = None          # nodes' (and the launcher's) Zenoh config
    router_config: str | None = None         # the router's (TLS, auth, access control)
    values: dict = field(default_factory=dict)   # template variables given on the command line
    planner_args: list[str] = field(default_factory=list)
    timeout_s: float = 300.0                 # [s run time]
    startup_timeout_s: float = 60.0          # [s wall]
    stall_s: float = STALL_S                 # [s wall]
    verbose: bool = False
    dry_run: bool = False
    view: int | None = None                  # also serve a Foxglove view on this port


def local_endpoint(listen: str) -> str:
    """The loopback endpoint for nodes on the router's host: tcp/0.0.0.0:7447 -> tcp/127.0.0.1:7447."""
    return re.sub(r"^(\w+)/(0\.0\.0\.0|\[::\])(:\d+)", r"\1/127.0.0.1\3", listen)


def plan(prof: Profile, opt: LaunchOptions) -> tuple[dict[str, list[str]], list[str]]:
    """(node name -> argv in start order, endpoints the nodes connect to)."""
    values = {**{k: str(v) for k, v in prof.defaults.items()},
              **{k: str(v) for k, v in opt.values.items() if v is not None}}
    if "world" in values:
        values["world_file"] = str(world_path(values["world"]))
        load_world(values["world"])                 # WorldError before anything starts
    listen = opt.listen or list(prof.listen)
    if prof.router:
        connect = opt.connect or [local_endpoint(next((e for e in listen if e.startswith("tcp/")),
                                                      listen[0]))]
    else:
        connect = opt.connect or list(prof.connect)
        if not connect and not opt.zenoh_config:
            raise ConfigError(f"profile {prof.name} runs no router: give --connect "
                              "tcp/<robot>:7447 (or a --zenoh-config that has connect endpoints)")
    common = [a for ep in connect for a in ("--connect", ep)] + ["--namespace", opt.namespace]
    if opt.zenoh_config:
        common += ["--zenoh-config", opt.zenoh_config]
    cmds = {}
    for spec in prof.nodes:
        if spec.needs and spec.needs not in values:
            continue
        args = list(spec.args)
        for var, extra in spec.if_set.items():
            if var in values:
                args += list(extra)
        if spec.name == "planner":
            args += opt.planner_args
        cmds[spec.name] = [sys.executable, "-m", spec.module, *_fill(args, values, prof, spec),
                           *common]
    if opt.view is not None:   # goals from the viewer are set: a launch session is live
        cmds["viewer"] = [sys.executable, "-m", "nodes.viewer",
                          *viewer_argv(opt.view, values.get("world_file"), "accept"), *common]
    return cmds, connect


def _fill(args: list[str], values: dict, prof: Profile, spec: NodeSpec) -> list[str]:
    out = []
    for a in args:
        for var in re.findall(r"{(\w+)}", a):
            if var not in values:
                raise ConfigError(f"profile {prof.name}, node {spec.name}: argument {a!r} needs "
                                  f"--{var.replace('_', '-')} (variables: {', '.join(VARIABLES)})")
            a = a.replace("{" + var + "}", values[var])
        out.append(a)
    return out


def launch(opt: LaunchOptions, stop: StopRequested | None = None) -> RunResult | None:
    """Start the profile's processes; drive a run if the profile says so; stop everything.

    Returns the run's result; for a serving profile (no run) None after SIGINT/SIGTERM, or
    a ``failed`` result if one of its processes died.
    """
    prof = load_profile(opt.profile)
    if prof.run and "world" not in opt.values and "world" not in prof.defaults:
        raise ConfigError(f"profile {prof.name} drives a run: give --world W")
    cmds, connect = plan(prof, opt)
    listen = opt.listen or list(prof.listen)
    if opt.dry_run:
        if prof.router:
            print(shlex.join(_router_argv(listen, opt.router_config)))
        for argv in cmds.values():
            print(shlex.join(argv))
        return None
    stop = stop or StopRequested()
    show = (lambda n, line: True) if opt.verbose else (
        lambda n, line: any(k in line for k in ("WARNING", "ERROR", "Traceback", "rror:", "ready as")))
    keys = Keys(opt.namespace)
    with Supervisor(show=show) as sup:
        if prof.router:
            sup.start("router", _router_argv(listen, opt.router_config))
            host, _, port = connect[0].partition("/")[2].rpartition(":")
            if connect[0].startswith("tcp/") and not wait_port(
                    int(port.split("#")[0]), 15.0, host.strip("[]"), abort=lambda: bool(sup.dead())):
                raise ConfigError(f"the router did not come up on {listen}: "
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


def _router_argv(listen: list[str], router_config: str | None) -> list[str]:
    argv = [sys.executable, "-m", "papf.router", *[a for ep in listen for a in ("--listen", ep)]]
    return argv + (["--zenoh-config", router_config] if router_config else [])


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
                      stall_s=opt.stall_s)
    try:
        if seq.handshake(world):
            seq.start(f"profile={prof.name} world={world.name}")
            seq.until_outcome()
    finally:
        result = _result(monitor, opt, prof, time.monotonic() - wall0)
        seq.end(result)
    return result


