"""Column maps: read an instrument's table export (oscilloscope, DAQ) as a :class:`Waveform`.

An oscilloscope or DAQ writes its own header (``Time,CH1,CH2``), often after a few lines of
settings and followed by a row of units, and stores times in ms or values in mV. A column
map says which column is the time axis and which column is which channel, each with an
optional scale to SI (seconds, volts). The same map has two spellings:

- inline, as ``msens compare|diagnose|check-waveform|convert --columns`` takes it::

      time=Time:ms,mss@13=CH1:mV,mss@18=CH2:0.001

  comma-separated ``TARGET=COLUMN[:SCALE]`` items, ``TARGET`` being ``time`` or a channel
  name (design.md §8) and ``SCALE`` a factor or a unit: ``s``, ``ms``, ``us``, ``ns`` for
  the time, ``V``, ``mV``, ``uV``, ``kV`` for channels;
- a TOML file (``--columns map.toml``), for column names with ``,``, ``=`` or ``:`` in them::

      schema = "msens.columns/1"
      [columns]
      time = "Time:ms"
      "mss@13" = "CH1:mV"
      "mss@18" = { column = "CH2", scale = 1e-3 }

Reading a text export with a map is :mod:`msens.io.mapped`. Every failure is an
:class:`~msens.errors.InputError` naming the map item or the file, line and column.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from msens.errors import InputError
from msens.io._files import MAX_TEXT_BYTES, read_bytes
from msens.io.waveform import (
    Channel,
)

SCHEMA = "msens.columns/1"

#: Scale to seconds of the time units a map may name.
TIME_UNITS: Mapping[str, float] = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}

#: Scale to volts of the value units a map may name (case matters: mV is not MV).
VALUE_UNITS: Mapping[str, float] = {"V": 1.0, "mV": 1e-3, "uV": 1e-6, "µV": 1e-6, "kV": 1e3}

#: The metadata a mapped waveform carries (the §8 ``units`` key that ``msens compare`` checks).
UNITS_KEY, UNITS = "units", "V"


TIME_TARGET = "time"

SYNTAX_HELP = ("items are TARGET=COLUMN[:SCALE] separated by commas, TARGET 'time' or a "
               "channel such as bead@13, SCALE a number or a unit")


@dataclass(frozen=True)
class ColumnSource:
    """One source column and the factor that turns its numbers into SI.

    Parameters
    ----------
    column : str
        Column name as in the file's header.
    scale : float
        Multiplies the column's numbers: to seconds for the time column, to volts for a
        channel (e.g. 1e-3 for ms or mV). Finite and nonzero; positive for the time.
    """

    column: str
    scale: float = 1.0


@dataclass(frozen=True)
class ColumnMap:
    """Which source column is the time axis and which is each channel.

    Parameters
    ----------
    time : ColumnSource
        The time column, scale to s (> 0).
    channels : tuple of (Channel, ColumnSource)
        Channels in output order with their column and scale to V.
    source : str
        Where the map came from (``--columns`` or a file), for messages.

    Raises
    ------
    InputError
        For no channel, a channel or column given twice, or a bad scale.
    """

    time: ColumnSource
    channels: tuple[tuple[Channel, ColumnSource], ...]
    source: str = "--columns"

    def __post_init__(self) -> None:
        if not self.channels:
            raise InputError(f"{self.source}: the column map names no channel; "
                             f"{SYNTAX_HELP}")
        _check_scale(self.time.scale, TIME_TARGET, self.source, positive=True)
        seen: dict[Channel, str] = {}
        used = {self.time.column: TIME_TARGET}
        for ch, col in self.channels:
            if ch in seen:
                raise InputError(f"{self.source}: target {ch.name} given twice; each channel "
                                 f"takes one column (repeats are {ch.kind}@{ch.particle}#2, "
                                 "#3, ...)")
            seen[ch] = col.column
            if col.column in used:
                raise InputError(f"{self.source}: column {col.column!r} is mapped twice "
                                 f"({used[col.column]} and {ch.name})")
            used[col.column] = ch.name
            _check_scale(col.scale, ch.name, self.source, positive=False)

    @property
    def columns(self) -> dict[str, str]:
        """Source column -> target (``"time"`` or the channel name), time first."""
        return {self.time.column: TIME_TARGET,
                **{col.column: ch.name for ch, col in self.channels}}

    def text(self) -> str:
        """The map in the inline form (what ``--columns`` takes), scales written out."""
        items = [(TIME_TARGET, self.time), *((ch.name, col) for ch, col in self.channels)]
        return ",".join(f"{t}={c.column}" + ("" if c.scale == 1.0 else f":{c.scale!r}")
                        for t, c in items)


def _check_scale(scale: object, target: str, source: str, *, positive: bool) -> None:
    ok = (isinstance(scale, int | float) and not isinstance(scale, bool)
          and math.isfinite(scale) and (scale > 0.0 if positive else scale != 0.0))
    if not ok:
        rule = "a finite number > 0" if positive else "a finite nonzero number"
        raise InputError(f"{source}: scale of {target} must be {rule}, got {scale!r}")


def _scale(text: str, target: str, item: str, source: str) -> float:
    """A scale written as a number or a unit name (the time's or the channels' units)."""
    units = TIME_UNITS if target == TIME_TARGET else VALUE_UNITS
    text = text.strip()
    if text in units:
        return units[text]
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{source}: {item!r}: scale {text!r} is not a number or a unit "
                         f"({', '.join(units)})") from None
    _check_scale(value, target, source, positive=target == TIME_TARGET)
    return value


def _target(name: str, source: str) -> Channel | None:
    """None for the time, else the channel ``name`` names."""
    if name == TIME_TARGET:
        return None
    try:
        return Channel.parse(name)
    except InputError as exc:
        raise InputError(f"{source}: target {name!r}: {exc}; or 'time'") from None


def _build(items: Sequence[tuple[str, ColumnSource]], source: str) -> ColumnMap:
    time: ColumnSource | None = None
    channels = []
    for name, col in items:
        if not col.column:
            raise InputError(f"{source}: target {name!r} has an empty column name")
        ch = _target(name, source)
        if ch is not None:
            channels.append((ch, col))
        elif time is not None:
            raise InputError(f"{source}: target 'time' given twice")
        else:
            time = col
    if time is None:
        raise InputError(f"{source}: the column map has no 'time=COLUMN' item: it must name "
                         "the time column")
    return ColumnMap(time=time, channels=tuple(channels), source=source)


def parse_column_map(text: str, source: str = "--columns") -> ColumnMap:
    """Parse the inline form ``time=Time:ms,bead@13=CH1:mV,...``.

    Parameters
    ----------
    text : str
        Comma-separated ``TARGET=COLUMN[:SCALE]`` items (see the module docstring).
    source : str
        Name of the map in messages.

    Returns
    -------
    ColumnMap

    Raises
    ------
    InputError
        Naming the offending item: no ``=``, an unknown target, a target or column given
        twice, a bad scale, no time or no channel.
    """
    items = []
    for raw in text.split(","):
        item = raw.strip()
        if not item:
            raise InputError(f"{source}: empty item in {text!r}; {SYNTAX_HELP}")
        name, sep, rest = item.partition("=")
        if not sep:
            raise InputError(f"{source}: item {item!r} has no '='; {SYNTAX_HELP}")
        name, rest = name.strip(), rest.strip()
        column, colon, scale = rest.rpartition(":")
        if not colon:
            column, scale = rest, ""
        _target(name, source)  # an unknown target is named before its scale
        value = _scale(scale, name, item, source) if colon else 1.0
        items.append((name, ColumnSource(column.strip(), value)))
    return _build(items, source)


def load_column_map(path: str | os.PathLike[str]) -> ColumnMap:
    """Read a column-map TOML file (schema ``msens.columns/1``; see the module docstring).

    Raises
    ------
    InputError
        For a missing file, bad TOML, a wrong schema or any bad entry, naming the key.
    """
    from msens.io.tomlreader import Table, read_document

    source = str(path)
    try:
        text = read_bytes(path, limit=MAX_TEXT_BYTES, what="column map file").decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{source}: not UTF-8 text (byte {exc.start})") from None
    root = read_document(text, source=source, schema=SCHEMA)
    table = root.table("columns", required=True)
    root.finish()
    items = []
    for name in table.keys():
        value = table.raw(name)
        where = f"columns.{name}"
        _target(name, f"{source}: '{where}'")
        if isinstance(value, str):
            column, colon, scale = value.rpartition(":")
            if not colon:
                column, scale = value, ""
            factor = _scale(scale, name, value, f"{source}: '{where}'") if colon else 1.0
            items.append((name, ColumnSource(column.strip(), factor)))
        elif isinstance(value, Mapping):
            sub = Table(value, where, source)
            column = sub.string("column", required=True)
            scale: Any = sub.raw("scale", 1.0)
            if isinstance(scale, str):
                scale = _scale(scale, name, scale, f"{source}: '{where}.scale'")
            _check_scale(scale, name, f"{source}: '{where}'", positive=name == TIME_TARGET)
            sub.finish()
            items.append((name, ColumnSource(column, float(scale))))
        else:
            raise table.error(name, f"must be \"COLUMN[:SCALE]\" or {{ column = ..., scale = "
                                    f"... }}, got {value!r}")
    return _build(items, source)


def column_map(spec: str | os.PathLike[str] | ColumnMap) -> ColumnMap:
    """A column map from what a user gives: a map, a ``.toml`` file, or the inline form."""
    if isinstance(spec, ColumnMap):
        return spec
    if isinstance(spec, os.PathLike) or str(spec).strip().lower().endswith(".toml"):
        return load_column_map(spec)
    return parse_column_map(str(spec))
