"""Typed access to one TOML table, with messages that name the key.

Every study key is read through :class:`Table`, which knows its dotted path in the file,
checks type and range, and remembers which keys were used so that unknown keys (typos) are
reported instead of silently ignored.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from typing import Any

from msens.errors import InputError, shorten

_TYPE_NAMES = {bool: "a boolean", int: "an integer", float: "a number", str: "a string"}


class Table:
    """One TOML table of a study file.

    Parameters
    ----------
    data : Mapping
        The parsed table.
    path : str
        Dotted location used in messages, e.g. ``"chain.wall"`` or ``"sensor[2].coil"``.
    source : str
        File name used in messages.
    """

    def __init__(self, data: Mapping[str, Any], path: str, source: str):
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: '{path}' must be a table, got {type(data).__name__}")
        self._data = data
        self._path = path
        self._source = source
        self._used: set[str] = set()

    def key(self, name: str) -> str:
        """Dotted name of ``name`` in this table, for messages."""
        return f"{self._path}.{name}" if self._path else name

    def error(self, name: str, message: str) -> InputError:
        """An :class:`InputError` about key ``name``."""
        return InputError(f"{self._source}: '{self.key(name)}' {message}")

    def has(self, name: str) -> bool:
        return name in self._data

    @property
    def data(self) -> Mapping[str, Any]:
        """The parsed table as given (not a copy: do not modify it)."""
        return self._data

    def keys(self) -> list[str]:
        """The keys present in this table."""
        return list(self._data)

    def _raw(self, name: str, default: Any, required: bool) -> Any:
        self._used.add(name)
        if name not in self._data:
            if required:  # a typo of it is named too: "'x.beads' is missing (unknown ...)"
                import difflib

                close = difflib.get_close_matches(name, [k for k in self._data
                                                         if k not in self._used], 1, 0.75)
                typo = f" (unknown key '{self.key(close[0])}' given)" if close else ""
                raise self.error(name, f"is missing{typo}")
            return default
        return self._data[name]

    def number(self, name: str, default: float | None = None, *, required: bool = False,
               low: float | None = None, high: float | None = None,
               low_open: bool = False, allow_none: bool = False) -> float:
        """A finite real number within ``[low, high]`` (``(low, high]`` if ``low_open``)."""
        value = self._raw(name, default, required)
        if value is None and allow_none:
            return None  # type: ignore[return-value]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(name, f"must be a number, got {shorten(value)}")
        given = value
        try:
            value = float(value)
        except OverflowError:  # an integer beyond float range (TOML integers are unbounded)
            value = math.inf if given > 0 else -math.inf
        if not math.isfinite(value):
            raise self.error(name, f"must be finite, got {shorten(given)}")
        # the value exactly as given (repr): "<= 1, got 1.0000001", never a rounded "got 1"
        if low is not None and (value <= low if low_open else value < low):
            rel = ">" if low_open else ">="
            raise self.error(name, f"must be {rel} {low:g}, got {shorten(given)}")
        if high is not None and value > high:
            raise self.error(name, f"must be <= {high:g}, got {shorten(given)}")
        return value + 0.0  # -0.0 -> 0.0 (a signed zero passes ">= 0" but not numpy's checks)

    def integer(self, name: str, default: int | None = None, *, required: bool = False,
                low: int | None = None, high: int | None = None) -> int:
        """An integer within ``[low, high]``."""
        value = self._raw(name, default, required)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(name, f"must be an integer, got {shorten(value)}")
        if low is not None and value < low:
            raise self.error(name, f"must be >= {low}, got {shorten(value)}")
        if high is not None and value > high:
            raise self.error(name, f"must be <= {high}, got {shorten(value)}")
        return value

    def string(self, name: str, default: str | None = None, *, required: bool = False,
               choices: Sequence[str] | None = None) -> str:
        """A string, optionally one of ``choices``."""
        value = self._raw(name, default, required)
        if value is None and default is None and not required:
            return None  # type: ignore[return-value]
        if not isinstance(value, str):
            raise self.error(name, f"must be a string, got {shorten(value)}")
        if choices is not None and value not in choices:
            allowed = ", ".join(repr(c) for c in choices)
            raise self.error(name, f"must be one of {allowed}, got {shorten(value)}")
        return value

    def label(self, name: str, *, required: bool = True) -> str:
        """A name that may become part of a file or folder name (a study's ``name`` is the
        default output folder ``out/<name>``): 1 to 100 characters, no path separator, no
        control character, not starting with a dot or a space (``..`` would climb out of
        ``out/``)."""
        value = self.string(name, required=required)
        if value is None:
            return value
        bad = [c for c in value if c in "/\\" or ord(c) < 32 or ord(c) == 127]
        if not 1 <= len(value) <= 100 or bad or value[0] in ". " or value[-1] == " ":
            raise self.error(name, "must be 1 to 100 characters without '/', '\\' or "
                             "control characters, not starting with '.' or a space (it "
                             f"names output folders such as out/<name>), got {shorten(value)}")
        return value

    def boolean(self, name: str, default: bool | None = None, *, required: bool = False) -> bool:
        value = self._raw(name, default, required)
        if not isinstance(value, bool):
            raise self.error(name, f"must be true or false, got {shorten(value)}")
        return value

    def table(self, name: str, *, required: bool = False) -> Table | None:
        """A sub-table, or None when absent and not required."""
        value = self._raw(name, None, required)
        if value is None:
            return None
        if not isinstance(value, Mapping):
            raise self.error(name, "must be a table ([...])")
        return Table(value, self.key(name), self._source)

    def tables(self, name: str) -> list[Table]:
        """An array of tables (``[[name]]``); empty when absent."""
        value = self._raw(name, [], False)
        if isinstance(value, Mapping) or not isinstance(value, list):
            raise self.error(name, "must be an array of tables ([[...]])")
        out = []
        for i, item in enumerate(value):
            if not isinstance(item, Mapping):
                raise self.error(f"{name}[{i + 1}]", "must be a table")
            out.append(Table(item, f"{self.key(name)}[{i + 1}]", self._source))
        return out

    def raw(self, name: str, default: Any = None) -> Any:
        """The untyped value (for values checked by the caller)."""
        return self._raw(name, default, False)

    def finish(self) -> None:
        """Raise on keys that were never read: they are typos or unsupported."""
        unknown = sorted(set(self._data) - self._used)
        if unknown:
            known = ", ".join(sorted(self._used)) or "(none)"
            raise InputError(
                f"{self._source}: unknown key '{self.key(unknown[0])}'; "
                f"allowed keys here: {known}"
            )


def read_document(text: str, *, source: str, schema: str) -> Table:
    """Parse a TOML document and check its ``schema`` key; the root :class:`Table`.

    A leading UTF-8 byte-order mark (as some Windows editors write) is ignored, as in the
    CSV reader.
    """
    text = text.removeprefix("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:  # tomllib parses nested arrays and inline tables recursively
        raise InputError(f"{source}: not valid TOML for msens: arrays or tables nested too "
                         "deeply (a study nests at most a few levels)") from None
    return document_table(data, source=source, schema=schema)


def document_table(data: Mapping[str, Any], *, source: str, schema: str) -> Table:
    """The root :class:`Table` of an already parsed document, its ``schema`` key checked."""
    root = Table(data, "", source)
    found = root.string("schema", required=True)
    if found != schema:
        raise root.error("schema", f"must be {schema!r}, got {shorten(found)}")
    return root
