"""A small TOML writer for the fuzz tests (the standard library reads TOML, not writes)."""

from __future__ import annotations

import json
import math
from typing import Any


def value(v: Any) -> str:
    """TOML text of one value."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # JSON string escapes are TOML basic-string escapes
    if isinstance(v, list):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML form for {type(v).__name__}")


def dumps(doc: dict, prefix: str = "") -> str:
    """TOML text of a document: plain keys first, then tables and arrays of tables."""
    lines, tables = [], []
    for k, v in doc.items():
        if isinstance(v, dict):
            tables.append((k, v, False))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v, True))
        else:
            lines.append(f"{json.dumps(k)} = {value(v)}")
    text = "".join(line + "\n" for line in lines)
    for k, v, array in tables:
        name = f"{prefix}.{json.dumps(k)}" if prefix else json.dumps(k)
        for item in (v if array else [v]):
            text += f"\n[[{name}]]\n" if array else f"\n[{name}]\n"
            text += dumps(item, name)
    return text
