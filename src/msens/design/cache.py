"""Sweep results in the artifact store: one small verified JSON file per content key.

A key is :func:`msens.store.content_key` of everything a result depends on (the code's
:data:`RESULT_VERSION`, the study, the design's geometry ...). The results live in the
sweep's own folder (a :class:`msens.store.Store` without a size bound: a resumed sweep needs
every one); each is written atomically with its checksum, so a sweep killed at any moment
leaves valid entries for the designs that finished and none for the others, and an entry
that is corrupted or altered is computed again, never used.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from msens.io.atomic import atomic_write_bytes
from msens.store import Store
from msens.store import content_key as _content_key

#: Bumped whenever a design function changes what it computes; part of every key.
RESULT_VERSION = "msens.design/2"


def content_key(*parts: Any) -> str:
    """:func:`msens.store.content_key` (SHA-256 hex) of ``parts`` and
    :data:`RESULT_VERSION`."""
    return _content_key([RESULT_VERSION, *parts])


class ResultCache:
    """Directory of ``<key>.json`` results (a :class:`msens.store.Store` there, unbounded).

    Parameters
    ----------
    directory : str or Path
        Created on first write.
    """

    def __init__(self, directory: str | Path):
        self.store = Store.at(directory, max_bytes=None)

    @property
    def directory(self) -> Path:
        """The results' folder (absolute)."""
        return self.store.directory

    def path(self, key: str) -> Path:
        return self.store.path(f"{key}.json")

    def get(self, key: str) -> Any | None:
        """The stored value, or None if absent (or not valid: it is then recomputed)."""
        return self.store.read_json(f"{key}.json")

    def put(self, key: str, value: dict) -> None:
        """Store ``value`` (a dict of JSON values; floats round-trip exactly)."""
        self.store.write_json(f"{key}.json", value, indent=None)


__all__ = ["RESULT_VERSION", "ResultCache", "atomic_write_bytes", "content_key"]
