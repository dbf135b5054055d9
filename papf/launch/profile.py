"""The node graph as data: launch profiles (TOML) resolved into the processes of one host.

A profile (``papf/launch/profiles/<name>.toml``, or any path; format in docs/architecture.md
"Launch profiles") names the host it runs on, the nodes there and their arguments
(``{variable}`` templates), whether that host runs the Zenoh router, whether it drives a
run, and the profile of the other host (``partner``) when the stack is split. ``papf run``
is the ``sim`` profile plus the run sequence; ``papf launch PROFILE`` any profile.
:func:`resolve` gives the process list both start (and ``--dry-run`` prints, as JSON).
"""

from __future__ import annotations

import importlib
import json
import re
import sys
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from common.errors import ConfigError
from common.optional import tomllib
from common.ports import Port, select
from common.syntax import toml_problem
from nodes.planner.registry import declared
from papf.launch.portrange import node_listen_port
from schemas.keys import TOPICS
from worlds import load_world, world_path

VARIABLES = ("world", "world_file", "seed", "planner", "planner_args", "record", "energy_model",
             "timeout_s", "realtime", "lockstep_timeout", "bridge_namespace", "objects",
             "view", "ros", "ros_domain", "cmd_vel_type", "ros_face", "ros_face_domain",
             "record_force", "ros_distro", "ros_face_distro", "record_format", "passing",
             "odom_hz", "pair_timeout")
ROUTER_MODULE = "papf.launch.router"
OBJECTS = ("none", "truth", "tracker")   # where the planner's obstacle tracks come from
OBJECT_PLANNERS = tuple(declared("uses_objects"))   # planners that use tracks: their default is truth
FLEET_NODES = ("energy_meter", "planner", "tracker", "lidar_sim")   # one per robot of [[robots]]
FLEET = ("each", "one")   # a robot node's processes in a fleet: one per robot, or one for all
PASSING = ("orca", "off")   # a fleet's passing layer (nodes.planner.passing); orca by default


def objects_for(planner: str | None, objects: str | None,
                allowed: tuple[str, ...] = OBJECTS) -> str:
    """``--objects`` as given, else for a planner that uses tracks the first of ``truth``,
    ``tracker`` the profile offers (``allowed``), else ``none``."""
    if objects is not None:
        return objects
    if planner in OBJECT_PLANNERS:
        return next((o for o in ("truth", "tracker") if o in allowed), "none")
    return "none"
# What the launcher of a run subscribes to and publishes (papf.launch.sequence), besides the
# profile's pose topic: it is a process of the graph too.
LAUNCHER_PORTS: tuple[Port, ...] = (
    ("out", "goal", "Goal"), ("out", "events", "Event"),
    ("in", "clock", "Clock"), ("in", "planner/status", "PlannerStatus"),
    ("in", "battery", "BatteryState"), ("in?", "events", "Event"), ("in?", "cmd_vel", "Twist"),
)


@dataclass(frozen=True)
class NodeSpec:
    name: str                               # liveliness name (``<ns>/alive/<name>``)
    module: str                             # ``python -m <module>``
    args: tuple[str, ...] = ()              # may use {variables}
    needs: str | None = None                # start only when this variable is set ("var=value":
                                            # only when it has that value)
    if_set: dict = field(default_factory=dict)   # variable (or "var=value") -> extra args
    fleet: str = "each"                     # a FLEET_NODES node in a fleet: a process per robot
                                            # (each), or one serving every robot (one:
                                            # --robots r1,r2,...) when their arguments agree


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    nodes: tuple[NodeSpec, ...]
    host: str = "local"                     # where this profile's processes run
    partner: str | None = None              # the other host's profile of a split stack
    router: bool = False                    # run the embedded router on this host
    listen: tuple[str, ...] = ()            # the router's endpoints
    connect: tuple[str, ...] = ()           # where this host's nodes connect (no router here)
    run: bool = False                       # drive a run from this host
    remote_nodes: tuple[str, ...] = ()      # nodes on the other host that a run waits for
    pose_topic: str = "odom"                # pose samples of the run summary
    defaults: dict = field(default_factory=dict)
    objects: tuple[str, ...] = OBJECTS      # the --objects sources this host can serve
    zenoh_mode: str = "client"              # nodes' mode: client (via the router) or peer (direct too)


@dataclass(frozen=True)
class Process:
    name: str
    host: str
    argv: tuple[str, ...]

    def to_json(self) -> dict:
        return {"name": self.name, "host": self.host, "argv": list(self.argv)}


@dataclass
class Resolved:
    """The processes of one host, router first, in start order; where the nodes connect."""

    profile: Profile
    processes: list[Process]
    connect: list[str]
    listen: list[str]

    @property
    def nodes(self) -> dict[str, list[str]]:
        return {p.name: list(p.argv) for p in self.processes if p.name != "router"}

    def to_json(self) -> str:
        return json.dumps({"profile": self.profile.name,
                           "processes": [p.to_json() for p in self.processes]}, indent=1)


def packaged_profiles() -> list[str]:
    root = resources.files("papf.launch") / "profiles"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


MAX_PROFILE_BYTES = 1024 * 1024   # [bytes] a launch profile (the packaged ones are ~2 KB)


def load_profile(name_or_path: str) -> Profile:
    """A packaged profile by name, or a TOML file by path; ConfigError says what is wrong."""
    path = Path(name_or_path)
    if not (path.suffix == ".toml" or "/" in name_or_path):
        path = Path(str(resources.files("papf.launch") / "profiles" / f"{name_or_path}.toml"))
    if not path.is_file():
        raise ConfigError(f"no launch profile {name_or_path!r}; packaged: "
                          f"{', '.join(packaged_profiles())} (or a path to a .toml file)")
    try:
        if path.stat().st_size > MAX_PROFILE_BYTES:
            raise ConfigError(f"launch profile {str(path)!r}: {path.stat().st_size:,} bytes; a "
                              f"profile has at most {MAX_PROFILE_BYTES:,}")
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
        nodes = tuple(NodeSpec(n["name"], n["module"], tuple(n.get("args", ())), n.get("needs"),
                               dict(n.get("if_set", {})), str(n.get("fleet", "each")))
                      for n in data.get("nodes", ()))
        bad = [n.name for n in nodes if n.fleet not in FLEET]
        if bad:
            raise ConfigError(f"launch profile {str(path)!r}: node {bad[0]}: fleet must be one of "
                              f"{', '.join(FLEET)}")
        prof = Profile(data.get("name", path.stem), data.get("description", ""), nodes,
                       data.get("host", "local"), data.get("partner"),
                       bool(data.get("router", False)), tuple(data.get("listen", ())),
                       tuple(data.get("connect", ())), bool(data.get("run", False)),
                       tuple(data.get("remote_nodes", ())), data.get("pose_topic", "odom"),
                       dict(data.get("defaults", {})), tuple(data.get("objects", OBJECTS)),
                       str(data.get("zenoh_mode", "client")))
        if prof.zenoh_mode not in ("client", "peer"):
            raise ConfigError(f"launch profile {str(path)!r}: zenoh_mode = {prof.zenoh_mode!r}; "
                              "valid: client, peer")
    except RecursionError:   # tomllib on thousands of nested arrays or tables
        raise ConfigError(f"launch profile {str(path)!r}: nested too deeply to be a "
                          "profile") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"launch profile {str(path)!r}: cannot read it as UTF-8 text "
                          f"({type(exc).__name__})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"launch profile {str(path)!r} is not valid TOML: "
                          f"{toml_problem(exc, text)} (see docs/architecture.md for the "
                          "format)") from None
    except (KeyError, TypeError, AttributeError, ValueError) as exc:
        raise ConfigError(f"launch profile {str(path)!r} is invalid: {type(exc).__name__}: "
                          f"{str(exc)[:200]} (see docs/architecture.md for the format)") from None
    if prof.pose_topic not in TOPICS:
        raise ConfigError(f"profile {prof.name}: pose_topic {prof.pose_topic!r} is not one of "
                          f"{sorted(TOPICS)}")
    if prof.router and not prof.listen:
        raise ConfigError(f"profile {prof.name}: router = true needs listen endpoints")
    return prof


@dataclass
class LaunchOptions:
    """What the command line adds to a profile (``papf launch``; ``papf run`` fills it too)."""

    profile: str
    connect: list[str] = field(default_factory=list)
    listen: list[str] = field(default_factory=list)
    namespace: str = "rosbot"
    zenoh_config: str | None = None          # nodes' (and the launcher's) Zenoh config
    router_config: str | None = None         # the router's (TLS, auth, access control)
    values: dict = field(default_factory=dict)   # template variables given on the command line
    planner_args: list[str] = field(default_factory=list)
    timeout_s: float = 300.0                 # [s run time]
    zenoh_mode: str | None = None            # client | peer; None: the profile's zenoh_mode
    extra_node_args: dict[str, list[str]] = field(default_factory=dict)
    startup_timeout_s: float = 60.0          # [s wall] for every node to become alive
    stall_s: float | None = None             # [s wall] no clock progress: stuck (None: default)
    verbose: bool = False
    dry_run: bool = False
    join: list[str] = field(default_factory=list)   # other hosts' routers this one connects to
    key_file: str | None = None              # a split's pairing key (common.runauth.load_pair_key)
    after_crash: str = "refuse"              # a run the robot is still in: refuse | resume | new


def local_endpoint(listen: str) -> str:
    """The loopback endpoint for nodes on the router's host: tcp/0.0.0.0:7447 -> tcp/127.0.0.1:7447."""
    return re.sub(r"^(\w+)/(0\.0\.0\.0|\[::\])(:\d+)", r"\1/127.0.0.1\3", listen)


def template_values(prof: Profile, opt: LaunchOptions) -> dict[str, str]:
    values = {**{k: str(v) for k, v in prof.defaults.items()},
              **{k: str(v) for k, v in opt.values.items() if v is not None}}
    values["planner_args"] = " ".join(opt.planner_args)
    values["timeout_s"] = f"{opt.timeout_s:g}"
    values["objects"] = objects_for(values.get("planner"), values.get("objects"), prof.objects)
    if values["objects"] not in prof.objects:
        raise ConfigError(f"profile {prof.name}: --objects {values['objects']} is not available "
                          f"here; valid: {', '.join(prof.objects)}")
    if "world" in values:
        values["world_file"] = str(world_path(values["world"]))
        load_world(values["world"])                 # WorldError before anything starts
    return values


def resolve(prof: Profile, opt: LaunchOptions) -> Resolved:
    """The profile's processes on this host with every argument filled in, router first."""
    values = template_values(prof, opt)
    listen = opt.listen or list(prof.listen)
    if prof.router:
        connect = opt.connect or [local_endpoint(next((e for e in listen if e.startswith("tcp/")),
                                                      listen[0]))]
    else:
        connect = opt.connect or list(prof.connect)
        if not connect and not opt.zenoh_config:
            raise ConfigError(f"profile {prof.name} runs no router: give --connect "
                              "tcp/<robot>:7447 (or a --zenoh-config that has connect endpoints)")

    taken = {int(m) for ep in listen for m in re.findall(r":(\d+)(?:#.*)?$", ep)}   # the router's

    def common(namespace: str) -> list[str]:
        args = [a for ep in connect for a in ("--connect", ep)] + ["--namespace", namespace]
        if opt.zenoh_config:
            args += ["--zenoh-config", opt.zenoh_config]
        if (opt.zenoh_mode or prof.zenoh_mode) == "peer":  # peers also talk directly: one loopback hop, not two
            port = node_listen_port(taken)   # the OS's pick (0), or one of --port-range
            args += ["--mode", "peer", "--listen", f"tcp/127.0.0.1:{port}"]
        return args
    procs = []
    if prof.router:
        argv = [sys.executable, "-m", ROUTER_MODULE, *[a for ep in listen for a in ("--listen", ep)]]
        argv += [a for ep in opt.join for a in ("--join", ep)]
        procs.append(Process("router", prof.host, tuple(argv + (
            ["--zenoh-config", opt.router_config] if opt.router_config else []))))
    fleet = fleet_of(values)
    for spec in prof.nodes:
        if fleet and spec.name in FLEET_NODES:   # one per robot, under the robot's name
            procs += _per_robot(spec, fleet, values, prof, opt, common)
            continue
        if fleet and spec.name in ("recorder", "viewer"):   # the first robot's namespace; a
            extra = ["--keys", "**"] if spec.name == "recorder" else []   # recording: all keys
            argv = _argv(spec, values, prof, opt, common(fleet[0].name) + extra)
        else:
            mine = dict(values)
            if spec.name in FLEET_NODES:   # one robot: its passing layer only when asked
                _passing(mine, 1, opt, prof)
            argv = _argv(spec, mine, prof, opt, common(opt.namespace))
        if argv:
            procs.append(Process(spec.name, prof.host, tuple(argv)))
    return Resolved(prof, procs, connect, listen)


def fleet_of(values: dict) -> tuple:
    """The world's ``[[robots]]`` (RobotSpec), or () for a single robot or no world."""
    return load_world(values["world"]).robots if "world" in values else ()


def _per_robot(spec: NodeSpec, fleet: tuple, values: dict, prof: Profile, opt: LaunchOptions,
               common) -> list[Process]:
    """A node of each robot: ``<robot>/<node>``, its namespace the robot's name, its planner
    the robot's own (else ``--planner``), its obstacle tracks as that planner needs. A node
    with ``fleet = "one"`` whose every robot gets the same arguments is one process instead,
    ``<node>`` on the run's namespace with ``--robots r1,r2,...`` (each robot's keys and token
    its own: the node serves each robot as its own process would)."""
    mine = {}
    for robot in fleet:
        mine[robot.name] = dict(values, planner=robot.planner or values.get("planner", ""))
        mine[robot.name]["objects"] = objects_for(mine[robot.name]["planner"],
                                                  opt.values.get("objects"), prof.objects)
        _passing(mine[robot.name], len(fleet), opt, prof)
    if spec.fleet == "one":
        alike = {tuple(_argv(spec, m, prof, opt, []) or ()) for m in mine.values()}
        if len(alike) == 1:
            argv = _argv(spec, next(iter(mine.values())), prof, opt,
                         [*common(opt.namespace), "--robots", ",".join(mine)])
            return [Process(spec.name, prof.host, tuple(argv))] if argv else []
    procs = []
    for robot in fleet:
        argv = _argv(spec, mine[robot.name], prof, opt, common(robot.name))
        if argv:
            procs.append(Process(f"{robot.name}/{spec.name}", prof.host, tuple(argv)))
    return procs


def _passing(mine: dict, robots: int, opt: LaunchOptions, prof: Profile) -> None:
    """The passing layer of a robot's planner (``passing``): ``orca`` by default in a fleet of
    two or more robots, else ``off`` (one robot: only when asked, for its people). On, the
    planner gets the others as obstacle tracks: the first of ``truth``, ``tracker`` the
    profile serves when ``--objects`` was not given."""
    mine.pop("passing", None)
    passing = opt.values.get("passing", "orca" if robots >= 2 else "off")
    if passing == "off":
        return
    if mine["objects"] == "none" and opt.values.get("objects") is None:
        mine["objects"] = next((o for o in ("truth", "tracker") if o in prof.objects), "none")
    if mine["objects"] == "none":
        raise ConfigError(f"--passing {passing} needs the other robots as obstacle tracks: "
                          "--objects truth or tracker (or --passing off)")
    mine["passing"] = passing


def _argv(spec: NodeSpec, values: dict, prof: Profile, opt: LaunchOptions,
          common: list[str]) -> list[str] | None:
    """A node's command line with every argument filled in; None if it ``needs`` an unset variable."""
    if spec.needs and not _holds(spec.needs, values):
        return None
    args = list(spec.args)
    for cond, extra in spec.if_set.items():
        if _holds(cond, values):
            args += list(extra)
    if spec.name == "planner":
        args += opt.planner_args
    return [sys.executable, "-m", spec.module, *_fill(args, values, prof, spec), *common,
            *opt.extra_node_args.get(spec.name, ())]


def _holds(cond: str, values: dict) -> bool:
    """``"var"``: the variable is set; ``"var=value"``: it is set to that value."""
    var, sep, value = cond.partition("=")
    return var in values and (not sep or values[var] == value)


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


def node_ports(module: str, argv: list[str] | tuple[str, ...]) -> tuple[Port, ...]:
    """The declared ports (``<module>.ports``) of a node started with ``argv``."""
    ports = importlib.import_module(f"{module}.ports")
    return select(ports.PORTS, ports.VARIANTS, argv, getattr(ports, "EXTRAS", {}))
