"""Message base: frozen dataclasses <-> msgpack, validation and JSON Schema.

A message class declares its fields with type annotations; the annotation decides the wire
form and the checks (:class:`Message`, docs/architecture.md "Messages"). Every encoded map
carries ``"_type": "papf/<Name>/v<N>"``. Used by every message of :mod:`schemas`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar, get_args, get_origin, get_type_hints

import msgpack
import numpy as np

from common.errors import SchemaError
from schemas.json_schema import json_type as _json_type

Floats = tuple[float, ...]
Points = tuple[tuple[float, float], ...]
Paths = tuple[Points, ...]
Strs = tuple[str, ...]

_F32 = np.dtype("<f4")


def meta(unit: str = "", doc: str = "", *, choices: tuple[str, ...] | None = None,
         nonfinite: bool = False, length: int | None = None) -> dict:
    """Field metadata: unit, description and constraints (see :class:`Message`)."""
    return {"unit": unit, "doc": doc, "choices": choices, "nonfinite": nonfinite,
            "length": length}


def field(default: Any = dataclasses.MISSING, **kwargs: Any) -> Any:
    """A dataclass field with :func:`meta` metadata; tuples default to ``()``."""
    md = meta(**kwargs)
    if default is dataclasses.MISSING:
        return dataclasses.field(metadata=md)
    return dataclasses.field(default=default, metadata=md)


def _kind(annotation: Any) -> str:
    args = get_args(annotation)
    if get_origin(annotation) is tuple and len(args) == 2 and args[1] is Ellipsis \
            and isinstance(args[0], type) and issubclass(args[0], Message):
        return "items"
    table = {int: "int", float: "float", str: "str", bool: "bool", Floats: "floats",
             Points: "points", Paths: "paths", Strs: "strs", np.ndarray: "f32array"}
    try:
        return table[annotation]
    except (KeyError, TypeError):
        raise TypeError(f"unsupported message field annotation {annotation!r}") from None


class Message:
    """Base of all messages. Subclasses are ``@message("Name", version)`` dataclasses.

    A message class declares its fields with type annotations; the annotation
    decides the wire form and the checks (docs/architecture.md "Messages"):

    ==============================  =====================================  ======================
    annotation                      wire form (msgpack)                    check
    ==============================  =====================================  ======================
    ``int``                         int                                    integer, no bool
    ``float``                       float                                  finite unless ``nonfinite``
    ``str``                         str                                    in ``choices`` if given
    ``bool``                        bool                                   bool
    ``Floats`` (tuple of float)     array of float                         finite, ``length`` if given
    ``Points`` (tuple of (x, y))    array of [x, y]                        finite pairs
    ``Paths`` (tuple of Points)     array of array of [x, y]               finite pairs
    ``Strs`` (tuple of str)         array of str
    ``np.ndarray``                  bytes, little-endian float32           length multiple of 4
    ``tuple[M, ...]`` (M a Message) array of M's maps (with ``_type``)     each one as M checks
    ==============================  =====================================  ======================

    Field metadata (``meta(unit=..., doc=..., choices=..., nonfinite=..., length=...)``)
    carries units and constraints; they land in the derived JSON Schema too.
    Every encoded map carries ``"_type": "papf/<Name>/v<N>"``; decoding checks it.
    """

    TYPE: ClassVar[str] = ""
    _FIELDS: ClassVar[tuple[tuple[str, str, dict], ...]] = ()
    _PLAIN: ClassVar[bool] = False   # no __post_init__ of its own: decoding may skip __init__

    # -- encoding ---------------------------------------------------------
    def to_dict(self) -> dict:
        """Plain-Python form (arrays as lists) — for JSON logs and reports."""
        out: dict[str, Any] = {}
        for name, kind, _ in self._FIELDS:
            value = getattr(self, name)
            if kind == "f32array":
                value = value.astype(float).tolist()
            elif kind == "items":
                value = [m.to_dict() for m in value]
            out[name] = value
        return out

    def to_wire(self, lists: bool = True) -> dict:
        """The msgpack map, ``_type`` first (``lists=False``: points and paths stay tuples,
        which msgpack packs as the same arrays — what :meth:`to_bytes` packs)."""
        out: dict[str, Any] = {"_type": self.TYPE}
        for name, kind, _ in self._FIELDS:
            value = getattr(self, name)
            if kind == "f32array":
                value = np.ascontiguousarray(value, dtype=_F32).tobytes()
            elif kind == "points" and lists:
                value = [list(p) for p in value]
            elif kind == "paths" and lists:
                value = [[list(p) for p in path] for path in value]
            elif kind == "items":
                value = [m.to_wire(lists) for m in value]
            out[name] = value
        return out

    def to_bytes(self) -> bytes:
        """msgpack bytes of this message (those of :meth:`to_wire`, byte for byte)."""
        return msgpack.packb(self.to_wire(lists=False), use_bin_type=True)

    @classmethod
    def from_normal(cls, **values: Any):
        """The message from values already in the form the constructor makes (Python floats;
        ``Floats``/``Points``/``Paths`` as tuples of them): no copy, no normalisation — for hot
        paths that build them so (the planner's debug state). Unknown/missing fields: TypeError."""
        bad = (values.keys() - cls._DEFAULTS.keys()) | (cls._REQUIRED - values.keys())
        if bad:
            raise TypeError(f"{cls.__name__}: unknown or missing fields {sorted(bad)}")
        if not cls._PLAIN:
            return cls(**values)
        obj = object.__new__(cls)
        obj.__dict__.update(cls._DEFAULTS, **values)
        return obj

    # -- decoding ---------------------------------------------------------
    @classmethod
    def from_bytes(cls, data: bytes | bytearray | memoryview):
        """Decode and validate; any problem raises :class:`SchemaError`."""
        try:
            wire = msgpack.unpackb(bytes(data), raw=False, strict_map_key=True)
        except Exception as exc:  # msgpack raises several unrelated types
            raise SchemaError(f"{cls.TYPE}: payload is not msgpack ({exc})") from None
        return cls.from_wire(wire)

    @classmethod
    def from_wire(cls, wire: Any):
        """Validate a decoded msgpack map and build the message."""
        if not isinstance(wire, dict):
            raise SchemaError(f"{cls.TYPE}: expected a map, got {type(wire).__name__}")
        got = wire.get("_type")
        if got != cls.TYPE:
            raise SchemaError(f"{cls.TYPE}: wrong message type {got!r} (expected {cls.TYPE!r})")
        values = {}
        complete = True
        for name, kind, md in cls._FIELDS:
            if name not in wire:
                if cls._default_of(name) is not dataclasses.MISSING:
                    complete = False
                    continue
                raise SchemaError(f"{cls.TYPE}: missing field {name!r}")
            value = wire[name]
            # fast path of the two commonest checks; anything else (and every error) via _check
            if kind == "float" and type(value) is float and (value - value == 0.0
                                                             or md.get("nonfinite")):
                values[name] = value
            elif kind == "int" and type(value) is int or kind == "str" and type(value) is str \
                    and (not md.get("choices") or value in md["choices"]):
                values[name] = value
            else:
                values[name] = _check(cls.TYPE, name, kind, md, value)
        if complete and cls._PLAIN:
            # every field checked and already in its normal form (what __post_init__ would
            # make of it): fill the frozen instance without __init__'s per-field setattr
            obj = object.__new__(cls)
            obj.__dict__.update(values)
            return obj
        return cls(**values)

    @classmethod
    def _default_of(cls, name: str) -> Any:
        f = cls.__dataclass_fields__[name]  # type: ignore[attr-defined]
        if f.default is not dataclasses.MISSING:
            return f.default
        if f.default_factory is not dataclasses.MISSING:
            return f.default_factory()
        return dataclasses.MISSING

    # -- schema -----------------------------------------------------------
    @classmethod
    def json_schema(cls) -> dict:
        """JSON Schema (draft 2020-12) of the decoded msgpack map.

        ``f32array`` fields are described as byte strings (``contentEncoding:
        binary``): validate decoded messages with bytes allowed as strings, or
        use :meth:`to_json_compatible` first.
        """
        props: dict[str, Any] = {"_type": {"const": cls.TYPE}}
        required = ["_type"]
        for name, kind, md in cls._FIELDS:
            props[name] = _json_type(kind, md)
            if cls._default_of(name) is dataclasses.MISSING:
                required.append(name)
        return {
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": cls.TYPE,
            "description": (cls.__doc__ or "").strip().split("\n\n")[0],
            "type": "object",
            "properties": props,
            "required": required,
        }

    @classmethod
    def to_json_compatible(cls, wire: dict) -> dict:
        """A decoded wire map with byte fields as latin-1 strings (for JSON Schema validation)."""
        return {k: (v.decode("latin-1") if isinstance(v, bytes) else v) for k, v in wire.items()}

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        for name, kind, _ in self._FIELDS:
            a, b = getattr(self, name), getattr(other, name)
            if kind == "f32array":
                if not np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True):
                    return False
            elif a != b and not (isinstance(a, float) and math.isnan(a) and math.isnan(b)):
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        _normalise(self)


def message(name: str, version: int):
    """Class decorator: make a frozen message dataclass typed ``papf/<name>/v<version>``."""

    def wrap(cls):
        cls = dataclasses.dataclass(frozen=True, eq=False)(cls)
        hints = get_type_hints(cls)
        cls._FIELDS = tuple(
            (f.name, kind, _item_meta(f.metadata or meta(), hints[f.name], kind))
            for f in dataclasses.fields(cls) for kind in (_kind(hints[f.name]),)
        )
        cls.TYPE = f"papf/{name}/v{version}"
        cls._PLAIN = cls.__post_init__ is Message.__post_init__
        cls._DEFAULTS = {f.name: f.default for f in dataclasses.fields(cls)}  # MISSING: required
        cls._REQUIRED = {k for k, v in cls._DEFAULTS.items() if v is dataclasses.MISSING}
        return cls

    return wrap


def _item_meta(md: Any, annotation: Any, kind: str) -> dict:
    """Field metadata, with the item class of a ``tuple[Message, ...]`` field under ``item``."""
    return {**md, "item": get_args(annotation)[0]} if kind == "items" else dict(md)


def _normalise(self) -> None:
    # Normalise containers so equal messages compare equal whatever was passed in.
    for name, kind, _ in self._FIELDS:
        value = getattr(self, name)
        if kind == "f32array":
            value = np.asarray(value, dtype=np.float32)
        elif kind == "floats":
            value = tuple(float(v) for v in value)
        elif kind in ("strs", "items"):
            value = tuple(value)
        elif kind == "points":
            value = tuple((float(p[0]), float(p[1])) for p in value)
        elif kind == "paths":
            value = tuple(tuple((float(p[0]), float(p[1])) for p in path) for path in value)
        else:
            continue
        object.__setattr__(self, name, value)


# -- validation -------------------------------------------------------------
def _check(type_name: str, name: str, kind: str, md: dict, value: Any) -> Any:
    where = f"{type_name}.{name}"
    if kind in _SEQUENCE_KINDS and not isinstance(value, (list, tuple)):
        raise SchemaError(f"{where}: expected an array, got {type(value).__name__}")
    return _CHECKERS[kind](where, value, md)


def _int(where: str, value: Any, md: dict) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise SchemaError(f"{where}: expected an integer, got {value!r}")
    return value


def _str(where: str, value: Any, md: dict) -> str:
    if not isinstance(value, str):
        raise SchemaError(f"{where}: expected a string, got {value!r}")
    if md.get("choices") and value not in md["choices"]:
        raise SchemaError(f"{where}: {value!r} is not one of {list(md['choices'])}")
    return value


def _bool(where: str, value: Any, md: dict) -> bool:
    if not isinstance(value, bool):
        raise SchemaError(f"{where}: expected true/false, got {value!r}")
    return value


def _f32array(where: str, value: Any, md: dict) -> np.ndarray:
    if not isinstance(value, (bytes, bytearray)) or len(value) % 4:
        raise SchemaError(f"{where}: expected little-endian float32 bytes, got "
                          f"{type(value).__name__} of length {_len(value)}")
    return np.frombuffer(bytes(value), dtype=_F32).copy()


def _floats(where: str, value: Any, md: dict) -> tuple[float, ...]:
    if md.get("length") is not None and len(value) != md["length"]:
        raise SchemaError(f"{where}: expected {md['length']} values, got {len(value)}")
    out = tuple(value)
    if all(type(v) is float and (v - v == 0.0 or md.get("nonfinite")) for v in out):
        return out   # what _float gives each of them
    return tuple(_float(where, v, md) for v in value)


def _strs(where: str, value: Any, md: dict) -> tuple[str, ...]:
    if not all(isinstance(v, str) for v in value):
        raise SchemaError(f"{where}: expected an array of strings")
    return tuple(value)


def _paths(where: str, value: Any, md: dict) -> Paths:
    return tuple(_points(f"{where}[{i}]", p, md) for i, p in enumerate(value))


def _points(where: str, value: Any, md: dict) -> Points:
    if not isinstance(value, (list, tuple)):
        raise SchemaError(f"{where}: expected an array of points, got {type(value).__name__}")
    out = []
    for i, p in enumerate(value):
        if not isinstance(p, (list, tuple)) or len(p) != 2:
            raise SchemaError(f"{where}[{i}]: expected an [x, y] pair, got {p!r}")
        out.append((_float(where, p[0], md), _float(where, p[1], md)))
    return tuple(out)


def _items(where: str, value: Any, md: dict) -> tuple:
    item = md["item"]
    try:
        return tuple(item.from_wire(v) for v in value)
    except SchemaError as exc:
        raise SchemaError(f"{where}: {exc}") from None


def _float(where: str, value: Any, md: dict) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SchemaError(f"{where}: expected a number, got {value!r}")
    value = float(value)
    if not md.get("nonfinite") and not math.isfinite(value):
        raise SchemaError(f"{where}: {value!r} is not allowed (must be finite)")
    return value


_SEQUENCE_KINDS = ("floats", "strs", "points", "paths", "items")
_CHECKERS = {"int": _int, "float": _float, "str": _str, "bool": _bool, "f32array": _f32array,
             "floats": _floats, "strs": _strs, "points": _points, "paths": _paths,
             "items": _items}


def _len(value: Any) -> str:
    try:
        return str(len(value))
    except TypeError:
        return "n/a"
