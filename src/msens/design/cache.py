"""Content-hash disk cache of sweep results: one small JSON file per key, written atomically.

A key is the SHA-256 of the canonical JSON of everything a result depends on (the code's
:data:`RESULT_VERSION`, the study, the design's geometry ...). A file appears only complete
(temporary file in the same directory, then :func:`os.replace`), so a sweep killed at any
moment leaves valid entries for the designs that finished and none for the others.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from msens.io.atomic import atomic_write_bytes, clean_stale
from msens.io.hashing import content_hash

#: Bumped whenever a design function changes what it computes; part of every key.
RESULT_VERSION = "msens.design/2"


def content_key(*parts: Any) -> str:
    """SHA-256 (hex) of the canonical JSON (:mod:`msens.io.hashing`) of ``parts`` and
    :data:`RESULT_VERSION`."""
    return content_hash([RESULT_VERSION, *parts])


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


__all__ = ["RESULT_VERSION", "ResultCache", "atomic_write_bytes", "content_key"]
