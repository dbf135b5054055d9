"""JSON Schema (draft 2020-12) of one message field, from its kind and metadata (:mod:`schemas.base`)."""

from __future__ import annotations

from typing import Any


def json_type(kind: str, md: dict) -> dict:
    """The schema of a field of ``kind`` (see :mod:`schemas.base`) with metadata ``md``."""
    if kind == "items":
        item = {k: v for k, v in md["item"].json_schema().items() if k != "$schema"}
        return {"type": "array", "items": item}
    number = {"type": "number"}
    pair = {"type": "array", "items": number, "minItems": 2, "maxItems": 2}
    out: dict[str, Any] = {
        "int": {"type": "integer"},
        "float": dict(number),
        "str": {"type": "string"},
        "bool": {"type": "boolean"},
        "floats": {"type": "array", "items": number},
        "strs": {"type": "array", "items": {"type": "string"}},
        "points": {"type": "array", "items": pair},
        "paths": {"type": "array", "items": {"type": "array", "items": pair}},
        "f32array": {"type": "string", "contentEncoding": "binary",
                     "description": "little-endian float32 array"},
    }[kind]
    if md.get("choices"):
        out["enum"] = list(md["choices"])
    if md.get("length") is not None:
        out["minItems"] = out["maxItems"] = md["length"]
    text = " ".join(x for x in (md.get("doc", ""), f"[{md['unit']}]" if md.get("unit") else "") if x)
    if text:
        out["description"] = (out.get("description", "") + " " + text).strip()
    return out
