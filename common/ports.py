"""A node's ports as data: what it subscribes to and what it publishes.

Each node declares ``PORTS`` in ``nodes/<node>/ports.py`` as ``(direction, key, message
type)`` tuples (:data:`Port`), and ``VARIANTS`` / ``EXTRAS`` where options change them
(:func:`select`). ``python -m nodes.<node> --help`` prints them (:func:`describe`), ``papf
node info`` shows them, and tests/unit/test_node_graph.py checks the launch profiles.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

# (direction, key, message type):
# - direction "in" (the node needs it), "in?" (optional: used when something publishes it)
#   or "out";
# - key: the suffix under the robot namespace ("scan" is <ns>/scan); "**" is every key (the
#   recorder); a "bridge:" prefix names a key of the zenoh-bridge-ros2dds namespace — the
#   real robot's ROS 2 topics, published and consumed outside this stack;
# - message type: the schema class name ("Scan", see schemas.keys.TOPICS) or, on bridge
#   keys, the ROS 2 type (CDR).
Port = tuple[str, str, str]
DIRECTIONS = ("in", "in?", "out")
BRIDGE = "bridge:"


def select(ports: Sequence[Port], variants: Mapping[tuple[str, str], Sequence[Port]],
           argv: Sequence[str], extras: Mapping[str, Sequence[Port]] = {}) -> tuple[Port, ...]:
    """The ports of a node started with ``argv``: the first variant whose option it sets
    (else ``ports``), plus the extras of the flags it sets.

    ``VARIANTS``: ``{(option, value): ports}`` (they replace ``PORTS``); ``EXTRAS``:
    ``{option: ports}`` for flags that add ports to whichever set applies (e.g.
    ``--truth-objects`` adds the ``objects`` output).
    """
    argv = list(argv)
    pairs = set(zip(argv, argv[1:], strict=False)) | {tuple(a.split("=", 1)) for a in argv
                                                        if a.startswith("--") and "=" in a}
    added = tuple(p for flag, more in extras.items() if flag in argv for p in more)
    for option, chosen in variants.items():
        if option in pairs:
            return tuple(chosen) + added
    return tuple(ports) + added


def describe(ports: Sequence[Port], variants: Mapping[tuple[str, str], Sequence[Port]] = {},
             extras: Mapping[str, Sequence[Port]] = {}) -> str:
    """Text table of the ports (and of each variant and extra) for a ``--help`` epilog."""
    blocks = [_table("ports (<ns> = --namespace, <bridge> = the ROS 2 bridge's):", ports)]
    for (option, value), chosen in variants.items():
        blocks.append(_table(f"ports with {option} {value}:", chosen))
    for flag, more in extras.items():
        blocks.append(_table(f"ports added by {flag}:", more))
    return "\n\n".join(blocks)


def _table(title: str, ports: Sequence[Port]) -> str:
    lines = [title]
    for direction, key, msg_type in ports:
        shown = f"<bridge>/{key[len(BRIDGE):]}" if key.startswith(BRIDGE) else f"<ns>/{key}"
        lines.append(f"  {direction:<4} {shown:<34} {msg_type}")
    return "\n".join(lines)


def plain(doc: str) -> str:
    """A module docstring as ``--help`` text: RST markup (``code``, :mod:`x`) made plain."""
    doc = re.sub(r":(?:mod|class|func|meth|data|attr):`~?([^`]+)`", r"\1", doc)
    return re.sub(r"``([^`]+)``", r"\1", doc)
