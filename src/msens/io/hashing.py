"""Content hashing: one canonical JSON form of nested values, and its SHA-256.

Every cache key of msens (field meshes, transducer sets, eddy-current responses, sweep
results) and a study's provenance hash is the SHA-256 of the canonical JSON text of what the
result depends on, so that equal inputs give equal keys in any process and on any machine:

- dataclasses become ``{"__type__": class name, field: value, ...}``;
- floats are written by ``repr`` (exact: 0.1 and 0.1 + 1e-17 differ), as strings;
- tuples, lists and numpy arrays become lists; numpy scalars Python numbers;
- dict keys become strings, enums their values, paths strings;
- the text has sorted keys and no spaces.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: Selects the dataclass fields that enter the canonical form: (field, value) -> bool.
FieldFilter = Callable[[dataclasses.Field, Any], bool]


def canonical(obj: Any, include: FieldFilter | None = None) -> Any:
    """JSON-ready, order-independent form of ``obj`` (see the module notes).

    Parameters
    ----------
    obj : any
        Nested dataclasses, enums, paths, dicts, sequences, numpy arrays and scalars, str,
        int, float, bool, None.
    include : callable, optional
        ``include(field, value)`` says whether a dataclass field enters (default: all); e.g.
        a mesh key leaves out the materials, on which a mesh does not depend.

    Returns
    -------
    object
        Made of dicts with str keys, lists, str, int, bool and None.
    """
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        values = ((f, getattr(obj, f.name)) for f in dataclasses.fields(obj))
        return {"__type__": type(obj).__name__,
                **{f.name: canonical(v, include) for f, v in values
                   if include is None or include(f, v)}}
    if isinstance(obj, enum.Enum):
        return canonical(obj.value, include)
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, dict):
        return {str(k): canonical(v, include)
                for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, tuple | list):
        return [canonical(v, include) for v in obj]
    if isinstance(obj, float):
        # repr of the object itself (numpy's float64 is a float): existing keys depend on it
        return repr(obj)
    if hasattr(obj, "tolist"):  # numpy arrays and scalars
        return canonical(obj.tolist(), include)
    return obj


def canonical_json(obj: Any, include: FieldFilter | None = None) -> str:
    """The canonical JSON text of ``obj``: :func:`canonical`, sorted keys, no spaces."""
    return json.dumps(canonical(obj, include), sort_keys=True, separators=(",", ":"))


def content_hash(obj: Any, digits: int | None = None,
                 include: FieldFilter | None = None) -> str:
    """SHA-256 (hex) of :func:`canonical_json` of ``obj``.

    Parameters
    ----------
    obj : any
        As for :func:`canonical`.
    digits : int, optional
        Keep the first ``digits`` hex digits (default: all 64).
    include : callable, optional
        As for :func:`canonical`.

    Returns
    -------
    str
    """
    return hashlib.sha256(canonical_json(obj, include).encode()).hexdigest()[:digits]


__all__ = ["FieldFilter", "canonical", "canonical_json", "content_hash"]
