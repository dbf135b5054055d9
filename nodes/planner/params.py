"""The planner's settings at run time (pure): list them, change them through ``--set``'s rules.

The planner node answers Zenoh queries on ``<ns>/planner/params`` with :func:`answer`;
the viewer's Parameters panel and ``papf param`` ask. A change is parsed and checked by
:func:`nodes.planner.registry.load_params`, as ``--set`` is, and takes effect at the next
cycle; a refused change leaves every value as it was.
"""

from __future__ import annotations

import dataclasses
import json

from common.errors import ConfigError
from common.runauth import RequestCheck
from nodes.planner.core import Planner
from nodes.planner.registry import load_params, settings_of

MAX_REQUEST_BYTES = 64 * 1024   # [bytes] a request (every setting at once is ~3 KB)


def current(name: str, planner: Planner) -> dict[str, object]:
    """Every setting of the running planner, ``table.field -> value``."""
    out = {f"apf.{f.name}": getattr(planner.apf, f.name) for f in dataclasses.fields(planner.apf)}
    algo = planner.strategy.params
    out.update({f"{name}.{f.name}": getattr(algo, f.name) for f in dataclasses.fields(algo)})
    return out


def _as_set(key: str, value: object) -> str:
    return f"{key}={repr(value) if isinstance(value, float) else value}"


def apply(name: str, planner: Planner, sets: list[str]) -> list[str]:
    """Apply ``--set`` strings on top of the current values; ConfigError if any is invalid
    (then nothing changes). Returns the names whose value changed."""
    before = current(name, planner)
    apf, algo = load_params(name, None, [_as_set(k, v) for k, v in before.items()] + list(sets))
    planner.set_params(apf, algo)
    after = current(name, planner)
    return [k for k in after if after[k] != before[k]]


def specs(name: str) -> dict[str, dict]:
    """Every setting's declared type and range, ``table.field -> {...}`` (for descriptors:
    the ROS 2 face's ``describe_parameters``): ``kind`` (float, int, bool, str), ``lo``,
    ``hi`` (None: unbounded), ``lo_open``, ``hi_open``, ``choices``, ``unit``, ``safety``,
    ``valid`` (the range in words, as errors say it)."""
    out = {}
    for field_name, (table, spec, _default) in settings_of(name).items():
        out[f"{table}.{field_name}"] = {
            "kind": spec.kind.__name__, "lo": spec.lo, "hi": spec.hi, "lo_open": spec.lo_open,
            "hi_open": spec.hi_open, "choices": list(spec.choices), "unit": spec.unit,
            "safety": spec.safety, "valid": spec.describe()}
    return out


def answer(name: str, planner: Planner, payload: bytes,
           check: RequestCheck | None = None) -> tuple[dict, list[str]]:
    """(reply, changed names) for one query payload; ``check``: the
    node's :class:`common.runauth.RequestCheck` (a change without this run's tag is refused).

    Names are ``table.name`` as ``--set`` takes them: ``apf.<field>`` for
    :class:`~nodes.planner.field.APFParams`, ``<planner>.<field>`` for the algorithm's own.
    Wire format (JSON): request ``{}`` (list; ``{"describe": true}`` adds ``"specs"``: each
    setting's type and range, :func:`specs`) or ``{"set": ["apf.v_max=0.3", ...], "nonce": N,
    "auth": TAG}`` (a change is signed with the run's key: :func:`common.runauth.sign_request`;
    a planner started without a key takes unsigned changes); reply
    ``{"planner": NAME, "params": {name: value}, "error": ""}`` (``error`` says why a change
    was refused).
    """
    error, changed, request = "", [], None
    try:
        if len(payload) > MAX_REQUEST_BYTES:
            raise ConfigError(f"request of {len(payload):,} bytes; at most {MAX_REQUEST_BYTES:,}")
        request = json.loads(payload.decode("utf-8")) if payload else {}
        sets = request.get("set", []) if isinstance(request, dict) else None
        if not isinstance(sets, list) or not all(isinstance(s, str) for s in sets):
            raise ConfigError('expected {"set": ["name=value", ...]}')
        if sets and check is not None and not check.ok(request):
            raise ConfigError("not signed with this run's key: parameters are changed only by "
                              "papf param set (or the viewer) of the user who launched the run")
        if sets:
            changed = apply(name, planner, sets)
    except (ConfigError, UnicodeDecodeError, ValueError) as exc:
        error = str(exc)
    reply = {"planner": name, "params": current(name, planner), "error": error}
    if isinstance(request, dict) and request.get("describe") is True:
        reply["specs"] = specs(name)
    return reply, changed
