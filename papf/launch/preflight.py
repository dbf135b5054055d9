"""Every check of a run's options that can be made before anything starts.

``papf run`` (and ``papf plan`` for what applies) call :func:`check_run` first, ``papf
launch`` :func:`check_launch` (the same checks for what its profile starts): a wrong
planner name (with a "did you mean"), a planner setting out of its range, a seed,
timeout or port out of range, a port someone else listens on (another stack's router
would receive our messages), a namespace that is not a plain key, a recording path in
a directory that does not exist, a 3-D world, or a world that cannot give a run
(:func:`worlds.checks.check_runnable`) — each is a ConfigError/WorldError: exit 2, one
line, and no process was started. The same specs serve as argparse ``type=`` checks
(:data:`SEED`, :data:`TIMEOUT`, :data:`PORT`).
"""

from __future__ import annotations

import difflib
import os
import re
from pathlib import Path

from common.errors import ConfigError, RecordingError
from common.outfiles import OutputError, check_output
from common.params import PORT, SEED, TIMEOUT, Spec, check_value
from nodes.planner.registry import DEFAULT_PLANNER, PLANNERS, load_params
from papf.launch import portrange
from papf.launch.supervisor import port_in_use
from schemas import Keys
from worlds import World
from worlds.checks import check_runnable

__all__ = ["SEED", "TIMEOUT", "PORT", "check_run", "check_launch", "planner_name", "namespace",
           "record_path", "endpoint"]


def planner_name(name: str) -> str:
    """``name`` if it is a planner; ConfigError with a "did you mean" (case too) otherwise."""
    if name in PLANNERS:
        return name
    lower = {p.lower(): p for p in PLANNERS}
    close = [lower[m] for m in difflib.get_close_matches(name.lower(), lower, n=1, cutoff=0.6)]
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ConfigError(f"unknown planner {name!r}{hint} (valid: {', '.join(sorted(PLANNERS))})")


def namespace(ns: str) -> str:
    """A namespace that makes valid Zenoh keys (``rosbot``, ``lab/r1``)."""
    try:
        Keys(ns)
    except ValueError as exc:
        raise ConfigError(f"--namespace: {exc}") from None
    return ns


def record_path(path: str | None, force: bool = False) -> None:
    """A recording can be created at ``path``: its directory exists and is writable, and no
    file is there unless ``force`` (:func:`common.outfiles.check_output`)."""
    if path is None:
        return
    p = Path(path)
    if os.path.lexists(p) and not p.is_dir():
        try:
            check_output(p, (), force)
        except OutputError as exc:
            raise ConfigError(f"--record {exc}") from None
    if p.is_dir():
        raise ConfigError(f"--record {path!r} is a directory; give a file name (F.mcap)")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise ConfigError(f"--record {path!r}: directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK):
        raise ConfigError(f"--record {path!r}: directory {str(parent)!r} is not writable")


def bag_path(path: str | None, force: bool = False) -> None:
    """A rosbag2 can be recorded at ``path`` (``--format ros2``): a new directory, or with
    ``force`` an existing rosbag2 (:func:`nodes.recorder.ros2_bag.check_bag_dir`)."""
    from nodes.recorder.ros2_bag import check_bag_dir

    if path is not None:
        try:
            check_bag_dir(path, force)
        except RecordingError as exc:
            raise ConfigError(f"--record {exc}") from None


def port_free(port: int | None) -> None:
    """An explicit port must be free: whatever listens there is not this run's router."""
    if port is None:
        return
    check_value("--port", port, PORT)
    portrange.check_port(port)
    if port_in_use(port):
        raise ConfigError(f"--port {port}: something already listens on 127.0.0.1:{port} "
                          "(another stack's Zenoh router, or another program); publishing "
                          "there would reach it. Give a free --port, or none to pick one")


def view_port(port: int | None) -> None:
    """The live view's port (``--view``) in range and free: the viewer would fail to bind
    after every other process started (or serve beside another program)."""
    if port is None:
        return
    check_value("--view", port, PORT)
    if port_in_use(int(port)):
        raise ConfigError(f"--view {port}: something already listens on 127.0.0.1:{port} "
                          "(another view, or another program); give a free port")


MAX_CONFIG_BYTES = 1024 * 1024   # [bytes] a Zenoh config file (they are a few KB)


def zenoh_config_file(path: str | None, flag: str) -> None:
    """A Zenoh config file (``--zenoh-config``, ``--router-config``) that exists, is a readable
    file of a sane size and parses as Zenoh's JSON5 — checked here, not by the processes that
    would each fail on it after the others started."""
    if path is None:
        return
    from common.transport import load_config_file  # zenoh: only when a file is given

    p = Path(path)
    if not p.is_file():
        what = "is a directory" if p.is_dir() else "does not exist"
        raise ConfigError(f"{flag} {_short(path)}: {what}; give a Zenoh JSON5 config file")
    try:
        size = p.stat().st_size
        if size > MAX_CONFIG_BYTES:
            raise ConfigError(f"{flag} {_short(path)}: {size:,} bytes is not a Zenoh config "
                              f"(at most {MAX_CONFIG_BYTES:,})")
        load_config_file(str(p))
    except ConfigError:
        raise
    except OSError as exc:
        raise ConfigError(f"{flag} {_short(path)}: cannot read it ({exc.strerror})") from None
    except Exception as exc:   # zenoh's parser: ZError, ValueError, UnicodeDecodeError
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ConfigError(f"{flag} {_short(path)}: not a valid Zenoh JSON5 config "
                          f"({first[:160]})") from None


def bridge_namespace(ns: str | None, ours: str) -> None:
    """``--bridge-namespace``: a plain key (a ROS namespace, leading ``/`` allowed) whose keys
    do not fall under our namespace (:meth:`BridgeTopics.check_separate`)."""
    if not ns or not ns.strip("/"):
        return
    from common.ros_link import BridgeTopics

    try:
        Keys(ns.strip("/"))
    except ValueError:
        raise ConfigError(f"--bridge-namespace {_short(ns)}: must be a plain key like 'robot1' "
                          "or '/lab/r1' (no empty parts, no spaces, no * $ ? #)") from None
    BridgeTopics(ns).check_separate(ours)


def planner_settings(planner: str, planner_args: list[str]) -> None:
    """``--set``/``--params`` items (as passed to the planner node) in their ranges."""
    sets, params, it = [], None, iter(planner_args)
    for flag in it:
        value = next(it, None)
        if flag == "--set" and value is not None:
            sets.append(value)
        elif flag == "--params" and value is not None:
            params = value
    load_params(planner, params, sets)


def check_run(world: World, planner: str, seed: int, timeout_s: float, port: int | None,
              ns: str, record: str | None, planner_args: list[str],
              spec_timeout: Spec = TIMEOUT, force: bool = False, view: int | None = None) -> None:
    """Every pre-start check of ``papf run`` (module doc)."""
    planner_name(planner)
    check_value("--seed", seed, SEED)
    check_value("--timeout", timeout_s, spec_timeout)
    planner_settings(planner, planner_args)
    for robot in world.robots:   # a fleet: each robot's own planner, if it names one
        if robot.planner is not None:
            try:
                planner_settings(planner_name(robot.planner), planner_args)
            except ConfigError as exc:
                raise ConfigError(f"world {world.name!r}, robot {robot.name!r}: {exc}") from None
    namespace(ns)
    record_path(record, force)
    if world.dims != 2:
        raise ConfigError(f"world {world.name!r} is 3-D: papf run simulates the ROSbot on 2-D "
                          "worlds; plan 3-D worlds offline with papf plan")
    check_runnable(world)
    port_free(port)
    view_port(view)


_ENDPOINT = re.compile(r"^(tcp|udp|tls|quic|ws)/(?P<host>\[[0-9a-fA-F:.]+\]|[^/:\[\]#]+):(?P<port>[^#/]*)(#.*)?$")


def endpoint(ep: str, flag: str) -> str:
    """A Zenoh locator ``proto/HOST:PORT`` with a port in 0..65535 (unix sockets taken as given)."""
    if ep.startswith("unixsock-stream/"):
        return ep
    m = _ENDPOINT.match(ep)
    if m is None:
        raise ConfigError(f"{flag} {_short(ep)}: must look like tcp/HOST:PORT (e.g. tcp/127.0.0.1:7447)")
    port = m.group("port")
    if not (port.isdigit() and int(port) <= 65535):
        raise ConfigError(f"{flag} {_short(ep)}: port {_short(port)} must be an integer in [0, 65535]")
    return ep


def _short(text: str) -> str:
    return repr(text if len(text) <= 60 else text[:57] + "...")


def check_launch(opt, prof) -> None:
    """Every pre-start check of ``papf launch`` — the same as ``papf run``'s (:func:`check_run`)
    for what the profile starts: timeouts, namespace, endpoints, seed, planner and its
    settings, the recording, and the world (runnable, 2-D). ``opt``: LaunchOptions."""
    check_value("--timeout", opt.timeout_s, TIMEOUT)
    check_value("--startup-timeout", opt.startup_timeout_s, TIMEOUT)
    if opt.stall_s is not None:
        check_value("--stall-timeout", opt.stall_s, TIMEOUT)
    namespace(opt.namespace)
    for flag, eps in (("--listen", opt.listen), ("--connect", opt.connect), ("--join", opt.join)):
        for ep in eps:
            endpoint(ep, flag)
    zenoh_config_file(opt.zenoh_config, "--zenoh-config")
    zenoh_config_file(opt.router_config, "--router-config")
    bridge_namespace(opt.values.get("bridge_namespace"), opt.namespace)
    view_port(opt.values.get("view"))
    if opt.join and not prof.router:
        raise ConfigError(f"--join connects this host's router to another's, and profile "
                          f"{prof.name} runs no router; use --connect for its nodes")
    values = {**prof.defaults, **opt.values}
    if values.get("seed") is not None:
        check_value("--seed", values["seed"], SEED)
    modules = {spec.module for spec in prof.nodes}
    if "nodes.planner" in modules or values.get("planner"):
        planner = str(values.get("planner") or DEFAULT_PLANNER)
        planner_name(planner)
        planner_settings(planner, opt.planner_args)
    if values.get("record_format") == "ros2":
        bag_path(values.get("record"), bool(values.get("record_force")))
    else:
        record_path(values.get("record"), bool(values.get("record_force")))
    if values.get("world"):
        from worlds import load_world

        world = load_world(str(values["world"]))
        if world.dims != 2:
            raise ConfigError(f"world {world.name!r} is 3-D: the stack drives the ROSbot on 2-D "
                              "worlds; plan 3-D worlds offline with papf plan")
        if world.robots and prof.run:
            raise ConfigError(f"world {world.name!r} has several robots ([[robots]]): papf run "
                              "drives a fleet; papf launch drives one robot (a fleet across "
                              "hosts: one launch per robot, each with its --namespace)")
        check_runnable(world)
