"""``papf new planner NAME [--from P]``: scaffold a planner plug-in (:mod:`nodes.planner.scaffold`)."""

from __future__ import annotations

import sys
from pathlib import Path

from common.errors import ConfigError
from nodes.planner.registry import DEFAULT_PLANNER, PLANNERS

INSTALLED_DIRS = ("site-packages", "dist-packages")   # where pip puts a non-editable install


def register(sub) -> None:
    """Add ``papf new planner`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("new", help="scaffold a new planner (its folder, its test)",
                       description="Scaffold a new part of the stack in this checkout.")
    kinds = p.add_subparsers(dest="kind", required=True, metavar="KIND")
    q = kinds.add_parser("planner", help="a planner plug-in copied from an existing planner",
                         description="Copy planner --from's folder to nodes/planner/NAME/ (its "
                                     "strategy renamed) and write tests/unit/test_planner_NAME.py; "
                                     "the registry finds it, `papf plan` and `papf run` take it "
                                     "as --planner NAME. Never overwrites. Exit 2 on a bad name.")
    q.add_argument("name", metavar="NAME", help="the new planner's name (lowercase, a-z 0-9 _)")
    q.add_argument("--from", dest="source", default=DEFAULT_PLANNER, metavar="P",
                   help=f"planner to copy: {' | '.join(PLANNERS)} (default {DEFAULT_PLANNER})")
    q.set_defaults(func=cmd_new_planner)


def check_checkout(root: Path) -> None:
    """ConfigError (one line) unless ``root`` is a source checkout that ``papf new`` may write in.

    A non-editable install (``pip install .``) puts the packages in site-packages, without
    ``pyproject.toml`` or ``tests/``: a planner scaffolded there would be lost at the next
    install and has no test tier to join.
    """
    if root.name in INSTALLED_DIRS or not (root / "pyproject.toml").is_file():
        raise ConfigError(f"{root} is an installed copy, not a checkout, and a new planner is "
                          "written into the package's source tree: clone the repository, run "
                          "`pip install -e .` in it, and run papf new there")


def cmd_new_planner(args) -> int:
    """``papf new planner``: scaffold a planner plug-in in this checkout; the exit code."""
    from nodes.planner.scaffold import new_planner, repo_root

    root = repo_root()
    check_checkout(root)
    here = Path.cwd().resolve() == root.resolve()   # elsewhere: say where the checkout is
    for path in new_planner(args.name, args.source, root):
        print(path.relative_to(root) if here else path)
    print(f"planner {args.name!r} from {args.source!r}: try `papf plan --world open --planner "
          f"{args.name}`, then edit {'' if here else f'{root}/'}nodes/planner/{args.name}/",
          file=sys.stderr)
    return 0
