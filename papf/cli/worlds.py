"""``papf worlds``: the packaged worlds, one line each."""

from __future__ import annotations

import shutil
import textwrap

from worlds import load_world, packaged_worlds


def register(sub) -> None:
    """Add ``papf worlds`` to the subcommands ``sub``."""
    p = sub.add_parser("worlds", help="list the packaged worlds")
    p.set_defaults(func=cmd_worlds)


def cmd_worlds(args) -> int:
    """``papf worlds``: list the packaged worlds with their descriptions; 0."""
    names = packaged_worlds()
    width = max(len(n) for n in names) + 2
    room = max(shutil.get_terminal_size((100, 24)).columns - width, 40)
    for name in names:
        text = " ".join(load_world(name).description.split())   # the whole text, one line
        print(f"{name:<{width}}{textwrap.shorten(text, room, placeholder=' …')}")
    return 0
