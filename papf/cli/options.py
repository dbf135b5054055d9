"""Options several ``papf`` commands share (same names, same meaning)."""

from __future__ import annotations

from nodes.planner.registry import DEFAULT_PLANNER, PLANNERS


def planner_help() -> str:
    """``--planner``'s help: every registered planner (nodes/planner/registry.py) and the default."""
    return f"{' | '.join(PLANNERS)} (default {DEFAULT_PLANNER})"


def add_world_and_planner(p, planner_help: str = "") -> None:
    """``--world`` (required) and ``--planner`` (help: :func:`planner_help` unless given)."""
    p.add_argument("--world", required=True, help="packaged world name or path to a .toml")
    p.add_argument("--planner", default=DEFAULT_PLANNER, help=planner_help or globals()["planner_help"]())


def add_planner_settings(p) -> None:
    """``--set NAME=VALUE`` (repeatable) and ``--params FILE.toml``."""
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter override, repeatable (e.g. --set v_max=0.3)")
    p.add_argument("--params", metavar="FILE.toml", help="planner parameters from a TOML file")
