"""Content-hash disk cache of sweep results: one small JSON file per key, written atomically.

A key is the SHA-256 of the canonical JSON of everything a result depends on (the code's
:data:`RESULT_VERSION`, the study, the design's geometry ...). A file appears only complete
(temporary file in the same directory, then :func:`os.replace`), so a sweep killed at any
moment leaves valid entries for the designs that finished and none for the others.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
from pathlib import Path
from typing import Any

from msens.io.atomic import atomic_write_bytes, clean_stale

#: Bumped whenever a design function changes what it computes; part of every key.
RESULT_VERSION = "msens.design/2"


def canonical(obj: Any) -> Any:
    """JSON-ready, order-independent form of nested dataclasses, enums, paths and floats."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {"__type__": type(obj).__name__,
                **{f.name: canonical(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if isinstance(obj, enum.Enum):
        return canonical(obj.value)
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, dict):
        return {str(k): canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, tuple | list):
        return [canonical(v) for v in obj]
    if isinstance(obj, float):
        return repr(obj)
    if hasattr(obj, "tolist"):
        return canonical(obj.tolist())
    return obj


def content_key(*parts: Any) -> str:
    """SHA-256 (hex) of the canonical JSON of ``parts`` and :data:`RESULT_VERSION`."""
    text = json.dumps(canonical([RESULT_VERSION, *parts]), sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


class ResultCache:
    """Directory of ``<key>.json`` results.

    Parameters
    ----------
    directory : str or Path
        Created on first write.
    """

    def __init__(self, directory: str | Path):
        self.directory = Path(directory)
        clean_stale(self.directory)  # temporary files of a killed sweep

    def path(self, key: str) -> Path:
        return self.directory / f"{key}.json"

    def get(self, key: str) -> Any | None:
        """The stored value, or None if absent (or unreadable: it is then recomputed)."""
        try:
            return json.loads(self.path(key).read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return None

    def put(self, key: str, value: Any) -> None:
        """Store ``value`` (JSON; floats round-trip exactly)."""
        atomic_write_bytes(self.path(key), json.dumps(value, sort_keys=True).encode())


__all__ = ["RESULT_VERSION", "ResultCache", "atomic_write_bytes", "canonical", "content_key"]
