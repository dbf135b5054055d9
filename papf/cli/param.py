"""``papf param list|get|set NODE [NAME [VALUE]]``: a running node's settings, live.

The client of the live parameter path (:mod:`nodes.planner.params`): ``list`` prints every
setting, ``get`` one, ``set`` changes one — checked here against its declared range first
(:func:`nodes.planner.registry.check_setting`: exit 2, one line, nothing sent), then signed
with the key the launcher of the namespace left for this user (:mod:`common.runauth`), and
checked again by the node. A safety setting is never taken below its floor (docs/planners.md
"Safety floors"). Exit code 0 done, 2 usage, refused or no answer.
"""

from __future__ import annotations

import json
import sys

from common.errors import ConfigError
from common.params import unknown_name
from common.transport import add_zenoh_args

# node -> the query its settings answer on (under <ns>/)
NODE_QUERIES = {"planner": "planner/params"}
ANSWER_S = 3.0   # [s] for the node to answer


def register(sub) -> None:
    """Add ``papf param`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("param", help="list, get or set a running node's settings (signed)",
                       description="A running node's settings: list them, get one, or set one "
                                   "(checked against its range, signed with your launch's run "
                                   "key). Exit code 0 done, 2 refused or no answer.")
    p.add_argument("action", choices=("list", "get", "set"))
    p.add_argument("node", metavar="NODE", help=f"the node: {', '.join(NODE_QUERIES)}")
    p.add_argument("name", nargs="?", metavar="NAME", help="setting (e.g. apf.v_max or v_max)")
    p.add_argument("value", nargs="?", metavar="VALUE", help="new value (set)")
    p.add_argument("--json", action="store_true", help="print the reply as one JSON object")
    add_zenoh_args(p)
    p.set_defaults(func=cmd_param)


def _usage(args) -> None:
    if args.node not in NODE_QUERIES:
        raise unknown_name(args.node, NODE_QUERIES, "node with settings")
    need = {"list": (False, False), "get": (True, False), "set": (True, True)}[args.action]
    if (args.name is not None) != need[0] or (args.value is not None) != need[1]:
        shape = {"list": "NODE", "get": "NODE NAME", "set": "NODE NAME VALUE"}[args.action]
        raise ConfigError(f"papf param {args.action} takes {shape}")


def _ask(session, key: str, request: dict) -> dict:
    from common.param_query import ask

    out = ask(session, key, request, ANSWER_S)
    if out is not None:
        return out
    raise ConfigError(f"no answer on {key} within {ANSWER_S:g} s: is the node running in this "
                      "namespace (papf launch / papf run), and may this identity query it?")


def _full_name(name: str, planner: str, params: dict) -> str:
    """``v_max`` -> ``apf.v_max``; a full ``table.name`` as it is."""
    if name in params:
        return name
    for table in ("apf", planner):
        if f"{table}.{name}" in params:
            return f"{table}.{name}"
    raise unknown_name(name, params, f"{planner} setting")


def cmd_param(args) -> int:
    """``papf param``: list, get or set a running node's settings; the exit code."""
    from common import runauth
    from common.text import safe_text
    from nodes.planner.registry import check_setting
    from papf.bus.session import open_session
    from schemas import Keys

    _usage(args)
    key = Keys(args.namespace).key(NODE_QUERIES[args.node])
    with open_session(args) as session:
        reply = _ask(session, key, {})
        params, planner = reply["params"], str(reply.get("planner", ""))
        if args.action != "list":
            name = _full_name(args.name, planner, params)
        if args.action == "set":
            table, _, short = name.rpartition(".")
            check_setting(planner, short, args.value, table)   # exit 2 before anything is sent
            request = runauth.sign_request({"set": [f"{name}={args.value}"]},
                                           runauth.read_key(args.namespace),
                                           runauth.read_run(args.namespace))
            reply = _ask(session, key, request)
            if reply.get("error"):
                raise ConfigError(f"{name}: refused by the {args.node}: {reply['error']}")
            params = reply["params"]
    shown = params if args.action == "list" else {name: params.get(name)}
    if args.json:
        print(json.dumps({"node": args.node, "planner": planner, "params": shown}))
    else:
        for k, v in sorted(shown.items()):   # a node's reply: shown, never run (common.text)
            print(f"{safe_text(str(k), 80)} = {safe_text(str(v), 200)}")
    sys.stdout.flush()
    return 0
