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

Reading a text export (:func:`read_mapped`): the header is the first line that names every
mapped column, split at ``,``, ``;`` or tabs (quotes around names are dropped); lines before
it are ignored, and up to :data:`MAX_SKIPPED_ROWS` rows right after it without numbers in the
mapped columns at all (a units row such as ``s,V,V``) are skipped. Other columns are ignored. The
time axis gets the same checks as a msens CSV file (uniform, increasing; the rounding of
fixed-format times is allowed for and undone). The waveform's metadata say ``units: V`` and
record the map (``columns``) and the file's name (``source_file``).

Every failure is an :class:`~msens.errors.InputError` naming the map item or the file, line
and column.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from msens.errors import InputError
from msens.io._files import read_bytes
from msens.io.csv import printed_resolution
from msens.io.waveform import (
    TIME_RTOL,
    Channel,
    Waveform,
    check_time,
    check_values,
    grid_deviation,
    uniform_axis,
)

SCHEMA = "msens.columns/1"
#: Scale to seconds of the time units a map may name.
TIME_UNITS: Mapping[str, float] = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}
#: Scale to volts of the value units a map may name (case matters: mV is not MV).
VALUE_UNITS: Mapping[str, float] = {"V": 1.0, "mV": 1e-3, "uV": 1e-6, "µV": 1e-6, "kV": 1e3}
#: Cell separators tried, in this order, on each candidate header line.
DELIMITERS = (",", ";", "\t")
#: Rows right after the header without numbers in the mapped columns that are skipped
#: (instruments print one or two: units, a probe setting); more is an error.
MAX_SKIPPED_ROWS = 5
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
        text = read_bytes(path).decode("utf-8-sig")
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


# ---------------------------------------------------------------------------------------
# Tables -> Waveform
# ---------------------------------------------------------------------------------------


def apply_column_map(
    table: Mapping[str, Any],
    cmap: ColumnMap,
    source: str,
    *,
    resolution: Mapping[str, float] | None = None,
    locate: Callable[[int], str] | None = None,
    metadata: Mapping[str, str] | None = None,
) -> Waveform:
    """Turn a foreign table into a :class:`Waveform` through a column map.

    Parameters
    ----------
    table : Mapping[str, array_like]
        Columns by name, each shape (nt,), in the instrument's units.
    cmap : ColumnMap
    source : str
        Name of the table in messages (e.g. the file).
    resolution : Mapping[str, float], optional
        Printed rounding of a column, in its own unit (see
        :func:`msens.io.csv.printed_resolution`); allowed for on the time axis.
    locate : callable, optional
        Sample index -> location text (``"scope.csv:14"``) for messages.
    metadata : Mapping[str, str], optional
        Extra metadata; ``units: V`` and ``columns`` (the map) are always set.

    Returns
    -------
    Waveform
        Time in s on a uniform axis, channels in V, in the map's order.

    Raises
    ------
    InputError
        For a mapped column that is missing, not one-dimensional or of another length,
        non-finite values or a time axis that is not uniform and increasing.
    """
    locate = locate or (lambda i: f"{source}: sample {i}")
    names = cmap.columns
    missing = [c for c in names if c not in table]
    if missing:
        present = ", ".join(repr(c) for c in table) or "(none)"
        raise InputError(f"{source}: column {missing[0]!r} (for {names[missing[0]]}) not "
                         f"found; columns present: {present}")
    arrays = {}
    for col, target in names.items():
        try:
            a = np.asarray(table[col], dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"{source}: column {col!r} (for {target}) is not numeric") \
                from None
        if a.ndim != 1:
            raise InputError(f"{source}: column {col!r} (for {target}) must be "
                             f"one-dimensional, got shape {a.shape}")
        arrays[col] = a
    nt = arrays[cmap.time.column].size
    for col, a in arrays.items():
        if a.size != nt:
            raise InputError(f"{source}: column {col!r} has {a.size} values but the time "
                             f"column {cmap.time.column!r} has {nt}")
    time = arrays[cmap.time.column] * cmap.time.scale
    printed = (resolution or {}).get(cmap.time.column, 0.0) * cmap.time.scale
    check_time(time, source, locate, resolution=printed)
    if grid_deviation(time)[1].max() > TIME_RTOL:
        time = uniform_axis(time)  # printed with too few digits: the rounding is undone
    data = np.empty((nt, len(cmap.channels)))
    for j, (ch, col) in enumerate(cmap.channels):
        data[:, j] = arrays[col.column] * col.scale
        check_values(data[:, j], f"{ch.name} (column {col.column!r})", source, locate)
    meta = {**(metadata or {}), UNITS_KEY: UNITS, "columns": cmap.text()}
    try:
        return Waveform(time, data, tuple(ch for ch, _ in cmap.channels), meta)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None


@dataclass(frozen=True)
class TextTable:
    """Columns read from a delimited text export.

    Attributes
    ----------
    columns : dict of str to ndarray, shape (nt,)
        The requested columns, float64, in the file's units.
    resolution : dict of str to float
        Printed rounding of each column (0 unless fixed-format), in its unit.
    lines : tuple of int
        1-based line number of each row.
    """

    columns: Mapping[str, np.ndarray]
    resolution: Mapping[str, float]
    lines: tuple[int, ...]


def parse_table(text: str, columns: Mapping[str, str], source: str) -> TextTable:
    """Find the header naming ``columns`` in a text export and read those columns.

    Parameters
    ----------
    text : str
        The file's text.
    columns : Mapping[str, str]
        Column name -> what it is for (used in messages), e.g. ``{"Time": "time"}``.
    source : str
        Name of the file in messages.

    Raises
    ------
    InputError
        No header line names all columns (the message names the first missing one), a
        column appears twice in the header, a row is too short or has a non-numeric cell
        (naming line and column), or there are no data rows.
    """
    lines = [line.removesuffix("\r") for line in text.split("\n")]
    header_index, delimiter, index = _find_header(lines, columns, source)
    rows: list[list[float]] = []
    cells: list[list[str]] = []
    numbers: list[int] = []
    skipped = 0
    wanted = list(index.items())
    for i in range(header_index + 1, len(lines)):
        line = lines[i]
        if not line.strip():
            continue
        parts = line.split(delimiter)
        values = [parts[j].strip() if j < len(parts) else None for _, j in wanted]
        numeric = [v is not None and _is_number(v) for v in values]
        if not all(numeric):
            if not rows and not any(numeric) and skipped < MAX_SKIPPED_ROWS:
                skipped += 1  # a units or settings row between header and data
                continue
            bad = numeric.index(False)
            col, j = wanted[bad]
            if values[bad] is None:
                raise InputError(f"{source}:{i + 1}: {len(parts)} cells, but column {col!r} "
                                 f"is column {j + 1} of the header (line {header_index + 1})")
            hint = (" (decimal commas are not read: export with a decimal point)"
                    if "," in values[bad] and delimiter != "," else "")
            raise InputError(f"{source}:{i + 1}: column {col!r} (for {columns[col]}): "
                             f"non-numeric cell {values[bad]!r}{hint}")
        rows.append([float(v) for v in values])
        cells.append(values)
        numbers.append(i + 1)
    if not rows:
        raise InputError(f"{source}: no data rows after the header (line {header_index + 1})")
    table = np.array(rows, dtype=np.float64)
    out = {col: table[:, k] for k, (col, _) in enumerate(wanted)}
    res = {col: printed_resolution([c[k] for c in cells]) for k, (col, _) in enumerate(wanted)}
    return TextTable(columns=out, resolution=res, lines=tuple(numbers))


def _unquote(cell: str) -> str:
    cell = cell.strip()
    if len(cell) >= 2 and cell[0] == cell[-1] and cell[0] in "\"'":
        return cell[1:-1].strip()
    return cell


def _find_header(lines: list[str], columns: Mapping[str, str],
                 source: str) -> tuple[int, str, dict[str, int]]:
    """Index of the header line, its delimiter and each wanted column's position."""
    first_time = None  # the first line naming the time column, for the message
    time_column = next(iter(columns))
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        for delimiter in DELIMITERS:
            cells = [_unquote(c) for c in line.split(delimiter)]
            if all(c in cells for c in columns):
                twice = next((c for c in columns if cells.count(c) > 1), None)
                if twice is not None:
                    raise InputError(f"{source}:{i + 1}: column {twice!r} appears twice in the "
                                     "header")
                return i, delimiter, {c: cells.index(c) for c in columns}
            if first_time is None and time_column in cells:
                first_time = (i, cells)
    if first_time is not None:
        i, cells = first_time
        missing = next(c for c in columns if c not in cells)
        raise InputError(f"{source}:{i + 1}: column {missing!r} (for {columns[missing]}) not in "
                         f"the header; columns present: {', '.join(repr(c) for c in cells)}")
    first = next((line for line in lines if line.strip()), "")
    raise InputError(f"{source}: no header line names the time column {time_column!r}; the "
                     f"first line is {first[:80]!r}")


def _is_number(cell: str) -> bool:
    if "_" in cell:  # float() takes '1_000'; an export has no digit separators
        return False
    try:
        float(cell)
    except ValueError:
        return False
    return True


def read_mapped(path: str | os.PathLike[str], cmap: ColumnMap | str) -> Waveform:
    """Read a delimited text export (CSV, TSV, TXT) through a column map.

    Parameters
    ----------
    path : path-like
        The instrument's file.
    cmap : ColumnMap or str
        The map, or its inline text or ``.toml`` file (see :func:`column_map`).

    Returns
    -------
    Waveform
        Time in s, channels in V; metadata ``units``, ``columns`` and ``source_file``.

    Raises
    ------
    InputError
        Naming the file, line and column (or the map item) of what is wrong.
    """
    cmap = column_map(cmap)
    p = Path(path)
    if p.suffix.lower() in (".npz", ".tdms"):
        raise InputError(f"{p}: column maps read text exports (CSV, TSV, TXT), not "
                         f"{p.suffix} files")
    raw = read_bytes(p)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        # Instrument software on Windows often writes Latin-1 (a µ in a unit row).
        text = raw.decode("latin-1")
    source = str(p)
    table = parse_table(text, cmap.columns, source)
    meta = {"source_file": p.name} if p.name.strip() == p.name and p.name.isprintable() else {}
    return apply_column_map(table.columns, cmap, source, resolution=table.resolution,
                            locate=lambda i: f"{source}:{table.lines[i]}", metadata=meta)


@dataclass(frozen=True)
class MappedFile(os.PathLike):
    """A text export and the column map to read it with; path-like, so it passes wherever a
    waveform file does (:func:`msens.io.read.read_waveform` applies the map).

    Parameters
    ----------
    path : Path
    columns : ColumnMap
    """

    path: Path
    columns: ColumnMap

    def __fspath__(self) -> str:
        return os.fspath(self.path)

    def __str__(self) -> str:
        return str(self.path)


def mapped(path: str | os.PathLike[str], columns: str | os.PathLike[str] | ColumnMap | None
           ) -> Path | MappedFile:
    """``path`` as the commands read it: with its column map if one is given.

    The map is parsed here, so a bad map fails before any work is done.
    """
    p = Path(path)
    return p if columns is None else MappedFile(p, column_map(columns))
