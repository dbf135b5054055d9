"""Options several ``papf`` commands share (same names, same meaning)."""

from __future__ import annotations

PLANNER_HELP = "apf | papf | arapf | wang | iapf (default apf)"


def add_world_and_planner(p, planner_help: str = PLANNER_HELP) -> None:
    """``--world`` (required) and ``--planner``."""
    p.add_argument("--world", required=True, help="packaged world name or path to a .toml")
    p.add_argument("--planner", default="apf", help=planner_help)


def add_planner_settings(p) -> None:
    """``--set NAME=VALUE`` (repeatable) and ``--params FILE.toml``."""
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter override, repeatable (e.g. --set v_max=0.3)")
    p.add_argument("--params", metavar="FILE.toml", help="planner parameters from a TOML file")
