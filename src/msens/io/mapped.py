"""Read an instrument's text export through a column map (:mod:`msens.io.columns`).

Reading a text export (:func:`read_mapped`): the header is the first line that names every
mapped column, split at ``,``, ``;`` or tabs (quotes around names are dropped); lines before
it are ignored, and up to :data:`msens.io.text_table.MAX_SKIPPED_ROWS` rows right after it
without numbers in the mapped columns at all (a units row such as ``s,V,V``) are skipped.
Other columns are ignored. The time axis gets the same checks as a msens CSV file (uniform,
increasing; the rounding of fixed-format times is allowed for and undone). The waveform's
metadata say ``units: V`` and record the map (``columns``) and the file's name
(``source_file``). Every failure is an :class:`~msens.errors.InputError` naming the file,
line and column.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from msens.errors import InputError
from msens.io._files import read_bytes
from msens.io.columns import UNITS, UNITS_KEY, ColumnMap, column_map
from msens.io.text_table import parse_table_bytes
from msens.io.waveform import (
    TIME_RTOL,
    Waveform,
    check_time,
    check_values,
    grid_deviation,
    uniform_axis,
)


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
    source = str(p)
    table = parse_table_bytes(read_bytes(p), cmap.columns, source)  # UTF-8, else Latin-1
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
