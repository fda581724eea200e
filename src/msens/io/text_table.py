"""A text export split into the columns a map names: the header line, skipped rows, cells.

Used by :mod:`msens.io.mapped`; see there for the rules.
"""

from __future__ import annotations

import codecs
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from msens.errors import InputError
from msens.io.csv import printed_resolution, read_numeric_block

#: Cell separators tried, in this order, on each candidate header line.
DELIMITERS = (",", ";", "\t")

#: Rows right after the header without numbers in the mapped columns that are skipped
#: (instruments print one or two: units, a probe setting); more is an error.
MAX_SKIPPED_ROWS = 5


@dataclass(frozen=True)
class TextTable:
    """Columns read from a delimited text export.

    Attributes
    ----------
    columns : dict of str to ndarray, shape (nt,)
        The requested columns, float64, in the file's units.
    resolution : dict of str to float
        Printed rounding of the time column (the first of ``columns``; 0 unless
        fixed-format), in its unit; the line-by-line reader also gives the others.
    lines : sequence of int, shape (nt,)
        1-based line number of each row (a tuple, or an int64 array from the fast reader).
    """

    columns: Mapping[str, np.ndarray]
    resolution: Mapping[str, float]
    lines: Sequence[int]


#: Lines searched for the header by the fast reader (further down: the line-by-line one).
_HEAD_LINES = 10_000


def parse_table_bytes(raw: bytes, columns: Mapping[str, str], source: str) -> TextTable:
    """:func:`parse_table` of a file's bytes: UTF-8 (a byte-order mark allowed), else Latin-1
    (instrument software on Windows often writes it: a µ in a unit row).

    The header and the rows right after it are found line by line; the data lines are read
    by a compiled parser (:func:`msens.io.csv.read_numeric_block`). Whatever that reader
    does not vouch for (a ragged or non-numeric line, NaN, a lone CR) is read again line by
    line by :func:`parse_table`, which names the line, so the rules and messages are the same.
    """
    encoding = "utf-8" if raw.isascii() or _is_utf8(raw) else "latin-1"
    start = 3 if encoding == "utf-8" and raw.startswith(codecs.BOM_UTF8) else 0
    table = _fast_table(raw, start, encoding, columns)
    if table is not None:
        return table
    return parse_table(raw[start:].decode(encoding), columns, source)


def _is_utf8(raw: bytes) -> bool:
    decoder = codecs.getincrementaldecoder("utf-8")()
    step = 1 << 20
    try:
        for at in range(0, len(raw), step):
            decoder.decode(raw[at:at + step], final=at + step >= len(raw))
    except UnicodeDecodeError:
        return False
    return True


def _fast_table(raw: bytes, start: int, encoding: str,
                columns: Mapping[str, str]) -> TextTable | None:
    """The table by the fast reader, or None where the line-by-line reader must look."""
    at, lineno = start, 1
    header = None
    while at < len(raw) and lineno <= _HEAD_LINES:  # the header: the first line naming all
        end = raw.find(b"\n", at)
        stop = len(raw) if end < 0 else end + 1
        line = raw[at:stop].decode(encoding).removesuffix("\n").removesuffix("\r")
        at, lineno = stop, lineno + 1
        if not line.strip():
            continue
        for delimiter in DELIMITERS:
            cells = [_unquote(c) for c in line.split(delimiter)]
            if all(c in cells for c in columns):
                if any(cells.count(c) > 1 for c in columns):
                    return None  # the line-by-line reader names the column
                header = delimiter, {c: cells.index(c) for c in columns}
                break
        if header is not None:
            break
    if header is None:
        return None
    delimiter, index = header
    skipped = 0
    while at < len(raw):  # units or settings rows between the header and the data
        end = raw.find(b"\n", at)
        stop = len(raw) if end < 0 else end + 1
        line = raw[at:stop].decode(encoding).removesuffix("\n").removesuffix("\r")
        if line.strip():
            parts = line.split(delimiter)
            values = [parts[j].strip() if j < len(parts) else None for j in index.values()]
            numeric = [v is not None and _is_number(v) for v in values]
            if all(numeric):
                break
            if any(numeric) or skipped >= MAX_SKIPPED_ROWS:
                return None
            skipped += 1
        at, lineno = stop, lineno + 1
    wanted = list(index.values())
    block = read_numeric_block(raw, at, lineno, delimiter, max(wanted) + 1, wanted,
                               exact=False, encoding=encoding)
    if block is None:
        return None
    return TextTable(columns={c: block.values[:, k] for k, c in enumerate(index)},
                     resolution={next(iter(index)): block.resolution},
                     lines=block.lines)


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
