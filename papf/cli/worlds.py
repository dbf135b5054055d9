"""``papf worlds``: the packaged worlds, one line each."""

from __future__ import annotations

from worlds import load_world, packaged_worlds


def register(sub) -> None:
    p = sub.add_parser("worlds", help="list the packaged worlds")
    p.set_defaults(func=cmd_worlds)


def cmd_worlds(args) -> int:
    for name in packaged_worlds():
        print(f"{name:24} {load_world(name).description.splitlines()[0][:90]}")
    return 0
