"""Options several ``papf`` commands share (same names, same meaning)."""

from __future__ import annotations

from common.errors import ConfigError
from nodes.planner.registry import DEFAULT_PLANNER, PLANNERS


def planner_help() -> str:
    """``--planner``'s help: every registered planner (nodes/planner/registry.py) and the default."""
    return f"{' | '.join(PLANNERS)} (default {DEFAULT_PLANNER})"


def add_world_and_planner(p, planner_help: str = "") -> None:
    """``--world`` (required), ``--start``/``--goal`` (with a map YAML) and ``--planner``
    (help: :func:`planner_help` unless given)."""
    p.add_argument("--world", required=True,
                   help="packaged world name, path to a .toml, or a ROS map .yaml (Nav2 "
                        "map_server format; then --start and --goal)")
    p.add_argument("--start", metavar="X,Y[,YAW]",
                   help="with a map .yaml: start pose [m, m, rad] (--start=-1,2 for negatives)")
    p.add_argument("--goal", metavar="X,Y", help="with a map .yaml: goal position [m]")
    p.add_argument("--planner", default=DEFAULT_PLANNER, help=planner_help or globals()["planner_help"]())


def resolve_world(args) -> str:
    """``args.world``, or for a map YAML the world file of ``--start``/``--goal`` on it
    (worlds/map_world.py); WorldError (exit 2) for --start/--goal without a map."""
    from common.errors import WorldError
    from worlds.map_world import is_map, map_world_file

    if is_map(args.world):
        args.world = map_world_file(args.world, args.start, args.goal)
    elif args.start is not None or args.goal is not None:
        raise WorldError("--start/--goal go with a map .yaml as --world; a world file "
                         "gives its own [robot] start and [goal]")
    return args.world


PORT_RANGE_HELP = ("every port the stack listens on inside LO-HI (e.g. 7447-7460): the router's "
                   "(unless --port) and each peer node's; for a lab firewall (docs/robot.md "
                   "\"Ports and firewalls\")")


def add_port_range(p) -> None:
    """``--port-range LO-HI`` (:mod:`papf.launch.portrange`): checked and applied by
    :func:`use_ports` before anything starts."""
    p.add_argument("--port-range", metavar="LO-HI", help=PORT_RANGE_HELP)


def use_ports(args, experiment: bool = False) -> None:
    """Apply ``--port-range`` (and an experiment's ``--port``) to this process and its
    children; ConfigError (exit 2, one line) before anything starts on a bad range, a
    ``--port`` outside it, or (``experiment``) a ``--port`` that runs at once would share."""
    from papf.launch import portrange

    rng = portrange.parse(args.port_range) if getattr(args, "port_range", None) else None
    port = getattr(args, "port", None)
    if rng is not None and port is not None and port not in rng:
        raise ConfigError(f"--port {port} is outside --port-range {rng}; give a port inside "
                          "it, or leave --port out")
    if experiment and port is not None and (getattr(args, "workers", 1) > 1
                                            or getattr(args, "scheduler", None)):
        raise ConfigError(f"--port {port} with --workers/--scheduler: runs at once need a "
                          "router port each; give --port-range LO-HI instead")
    portrange.use(rng, port if experiment else None)


def add_planner_settings(p) -> None:
    """``--set NAME=VALUE`` (repeatable) and ``--params FILE.toml``."""
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter override, repeatable (e.g. --set v_max=0.3)")
    p.add_argument("--params", metavar="FILE.toml", help="planner parameters from a TOML file")
