"""A planner plug-in's own debug output, declared as data (pure).

A strategy lists what it shows beside the generic parts of every plan (force, mode,
temporary goal, predicted path, ...) as :class:`DebugField` declarations on its ``DEBUG``;
its :class:`~nodes.planner.core.Plan` returns this cycle's values in one mapping,
``Plan.debug`` (name -> value). The core checks them against the declarations
(:func:`debug_values`: an undeclared name or a value of the wrong shape raises
:class:`DebugError`, so a plug-in's mistake fails its tests instead of reaching the bus) and
puts them in ``PlannerState.debug`` with their kind, unit and style, which is all a consumer
draws by (docs/architecture.md "Extending").
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass, field

import numpy as np

from schemas.planner_state import DEBUG_KINDS, GREY, DebugValue

NAME_RE = re.compile(r"^[a-z][a-z0-9_]{0,47}$")


class DebugError(ValueError):
    """A plug-in's debug declaration or value is not what it should be (a programming error)."""


@dataclass(frozen=True)
class Style:
    """How every consumer draws a field: colour (r, g, b, a in 0..1), size [m] (line
    thickness, marker diameter), dashed lines."""

    colour: tuple[float, float, float, float] = GREY
    size: float = 0.05
    dashed: bool = False


@dataclass(frozen=True)
class DebugField:
    """One field of a plug-in's debug output.

    ``kind``: ``points`` (an (K, 2) array of positions), ``paths`` (polylines: a sequence of
    (K, 2) arrays or one (N, K, 2) array), ``point`` (one (x, y), or () for none), ``scalar``
    (a number, nan = none) or ``count`` (a whole number, signed). Positions are world-frame
    metres; extra columns beyond x, y are dropped. ``label``: words in legends ('' = name).
    """

    name: str
    kind: str
    unit: str = ""
    doc: str = ""
    label: str = ""
    style: Style = field(default_factory=Style)

    @property
    def caption(self) -> str:
        return self.label or self.name.replace("_", " ")


def check_declarations(owner: str, fields: tuple) -> None:
    """DebugError unless ``fields`` are DebugFields with distinct valid names, known kinds and
    a drawable style."""
    seen = set()
    for f in fields:
        if not isinstance(f, DebugField):
            raise DebugError(f"{owner}: DEBUG holds {f!r}; use nodes.planner.debug.DebugField")
        if not NAME_RE.match(f.name) or f.name in seen:
            raise DebugError(f"{owner}: debug field name {f.name!r} is not a fresh lowercase "
                             "identifier")
        if f.kind not in DEBUG_KINDS:
            raise DebugError(f"{owner}: debug field {f.name!r} has kind {f.kind!r}; valid: "
                             f"{', '.join(DEBUG_KINDS)}")
        c, size = f.style.colour, f.style.size
        if len(c) != 4 or not all(0.0 <= x <= 1.0 for x in c) or not 0.0 < size < 100.0:
            raise DebugError(f"{owner}: debug field {f.name!r}: style colour must be 4 values "
                             f"in 0..1 and size in (0, 100) m, got {c}, {size}")
        seen.add(f.name)


def debug_values(owner: str, fields: tuple, values: dict) -> tuple[DebugValue, ...]:
    """The cycle's ``values`` (name -> value) as messages, one per declared field in
    declaration order (a field not given this cycle: empty). DebugError on an undeclared
    name or a value that is not of the field's kind."""
    if values and not values.keys() <= _names(fields):
        unknown = sorted(values.keys() - _names(fields))
        raise DebugError(f"{owner}: debug {unknown} not declared; declared: "
                         f"{[f.name for f in fields] or 'none'} (the strategy's DEBUG)")
    return tuple(DebugValue.from_normal(**_constant(f), **_CONVERT[f.kind](
        owner, f.name, values.get(f.name))) for f in fields)


@functools.lru_cache(maxsize=256)
def _names(fields: tuple) -> frozenset:
    return frozenset(f.name for f in fields)


@functools.lru_cache(maxsize=1024)
def _constant(f: DebugField) -> dict:
    """What a field's message holds every cycle: its declaration, in the message's form."""
    s = f.style
    return {"name": f.name, "kind": f.kind, "unit": f.unit, "label": f.caption,
            "colour": tuple(float(x) for x in s.colour), "size": float(s.size),
            "dashed": bool(s.dashed)}


def _array(owner: str, name: str, value, ndim: int) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise DebugError(f"{owner}: debug {name!r} is not numbers: {value!r:.80}") from None
    if arr.size == 0:
        return arr.reshape((0,) * ndim)
    if arr.ndim != ndim or arr.shape[-1] < 2:
        raise DebugError(f"{owner}: debug {name!r} has shape {arr.shape}; expected "
                         f"{'(K, 2)' if ndim == 2 else '(2,)' if ndim == 1 else '(N, K, 2)'}")
    if not np.isfinite(arr[..., :2]).all():
        raise DebugError(f"{owner}: debug {name!r} has a non-finite coordinate")
    return arr


def _empty(value) -> bool:
    """None, or an empty sequence or array (the common cycle: nothing to show)."""
    return value is None or (isinstance(value, (list, tuple, np.ndarray)) and len(value) == 0)


def _points(owner: str, name: str, value) -> dict:
    if _empty(value):
        return {"points": ()}
    arr = _array(owner, name, value, 2)
    return {"points": tuple(map(tuple, arr[:, :2].tolist()))}


def _point(owner: str, name: str, value) -> dict:
    if _empty(value):
        return {"points": ()}
    arr = _array(owner, name, value, 1)
    return {"points": (tuple(arr[:2].tolist()),) if arr.size else ()}


def _paths(owner: str, name: str, value) -> dict:
    if _empty(value):
        return {"paths": ()}
    if isinstance(value, np.ndarray) and value.ndim == 3:   # one conversion for all of them
        arr = _array(owner, name, value, 3)
        return {"paths": tuple(tuple(map(tuple, p)) for p in arr[:, :, :2].tolist())}
    return {"paths": tuple(_points(owner, name, p)["points"] for p in value)}


def _scalar(owner: str, name: str, value) -> dict:
    if value is None:
        return {"value": math.nan}
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        raise DebugError(f"{owner}: debug {name!r} is a scalar; got {value!r:.80}")
    if math.isinf(value):
        raise DebugError(f"{owner}: debug {name!r} is infinite (nan = none; else finite)")
    return {"value": float(value)}


def _count(owner: str, name: str, value) -> dict:
    if value is None:
        return {"value": 0.0}
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
            or abs(value) > 2 ** 53:
        raise DebugError(f"{owner}: debug {name!r} is a count (a whole number); "
                         f"got {value!r:.80}")
    return {"value": float(value)}


_CONVERT = {"points": _points, "point": _point, "paths": _paths, "scalar": _scalar,
            "count": _count}
