"""A message from its fields as a user types them (``papf topic pub KEY VALUE``), pure.

VALUE is YAML or JSON (JSON is YAML), the fields of the message like ``ros2 topic pub``
takes them: ``"{linear: {x: 0.2}, angular: {z: 0.5}}"``. Fields not given take their
default (numbers 0, strings empty, arrays empty); an unknown field, a wrong type or a
non-finite number where it is not allowed is a :class:`~common.errors.ConfigError` that
names the field and what is valid.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import yaml

from common.errors import ConfigError, SchemaError
from common.syntax import yaml_problem

_NUMPY = {"float32": np.float32, "float64": np.float64, "int8": np.int8, "uint8": np.uint8,
          "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
          "int64": np.int64, "uint64": np.uint64, "byte": np.uint8, "char": np.uint8,
          "bool": np.bool_}
_INTS = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char"}


def parse_value(text: str) -> dict:
    """VALUE -> a mapping of fields (ConfigError if it is not one)."""
    try:
        value = yaml.safe_load(text) if text.strip() else {}
    except RecursionError:   # thousands of nested brackets
        raise ConfigError("VALUE is nested too deeply to be a message") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"VALUE {text!r} is not YAML/JSON: {yaml_problem(exc, text)}") from None
    if value is None:
        value = {}
    if not isinstance(value, dict):
        raise ConfigError(f"VALUE {text!r} must be a mapping of fields, e.g. \"{{v: 0.2}}\"")
    return value


# -- ROS 2 messages (rosbags) -----------------------------------------------------------------
def ros_message(store, typename: str, fields: dict, where: str = ""):
    """A rosbags message of ``typename`` with ``fields`` set, the rest default."""
    if typename not in store.fielddefs:
        raise ConfigError(f"{typename!r} is not a ROS 2 message type rosbags knows "
                          "(e.g. geometry_msgs/msg/Twist)")
    _, defs = store.fielddefs[typename]
    names = [n for n, _ in defs]
    unknown = sorted(set(fields) - set(names))
    if unknown:
        raise ConfigError(f"{typename}{where}: no field {', '.join(unknown)}; fields: "
                          f"{', '.join(names)}")
    values = {name: _ros_field(store, spec, fields.get(name), f"{where}.{name}" if where else name)
              for name, spec in defs}
    return store.types[typename](**values)


def _ros_field(store, spec, value, where: str):
    kind, detail = spec
    kind = int(kind)
    if kind == 2:                                   # nested message
        if value is not None and not isinstance(value, dict):
            raise ConfigError(f"{where}: expected a mapping of {detail} fields, got {value!r}")
        return ros_message(store, detail, value or {}, f" {where}")
    if kind == 1:                                   # base type
        return _base(detail[0], value, where)
    inner, size = detail                            # 3 array, 4 sequence
    items = [] if value is None else value
    if not isinstance(items, list):
        raise ConfigError(f"{where}: expected a list, got {items!r}")
    if kind == 3 and len(items) not in (0, size):
        raise ConfigError(f"{where}: expected {size} items, got {len(items)}")
    if kind == 3 and not items:
        items = [None] * size
    if int(inner[0]) == 1 and inner[1][0] in _NUMPY:
        return np.array([_base(inner[1][0], v, f"{where}[{i}]") for i, v in enumerate(items)],
                        dtype=_NUMPY[inner[1][0]])
    return [_ros_field(store, inner, v, f"{where}[{i}]") for i, v in enumerate(items)]


def _base(name: str, value, where: str):
    if name == "string":
        if value is None:
            return ""
        if not isinstance(value, str):
            raise ConfigError(f"{where}: expected a string, got {value!r}")
        return value
    if name == "bool":
        if value is None:
            return False
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: expected true or false, got {value!r}")
        return value
    if value is None:
        return 0 if name in _INTS else 0.0
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{where}: expected a number ({name}), got {value!r}")
    if name in _INTS:
        if not float(value).is_integer():
            raise ConfigError(f"{where}: expected an integer ({name}), got {value!r}")
        return int(value)
    return float(value)


# -- our messages (schemas) -------------------------------------------------------------------
def our_message(msg_type, fields: dict[str, Any]):
    """One of our messages from its fields (``stamp_ns`` 0 if not given), checked by its schema."""
    fields = {"stamp_ns": 0, **fields}
    try:
        msg = msg_type(**fields)
    except TypeError as exc:
        raise ConfigError(f"{msg_type.__name__}: {exc}") from None
    try:
        return msg_type.from_bytes(msg.to_bytes())        # the schema's own validation
    except (SchemaError, ValueError, TypeError) as exc:
        raise ConfigError(f"{msg_type.__name__}: {exc}") from None

