"""Waveform CSV files (design.md §8).

::

    # msens-waveform: 1
    # drop_height_m: 0.0072
    time_s,bead@13,bead@18
    -1e-05,0.0012,-0.0003

Rules the reader enforces, each failure an :class:`~msens.errors.InputError` naming
``file:line``:

- lines starting with ``#`` before the header are metadata ``key: value`` (a bare ``#`` is
  ignored); ``# msens-waveform: 1`` is the format version, checked and not kept;
- the header's first column is ``time_s``, the others channel names (see
  :class:`~msens.io.waveform.Channel`), no duplicates;
- every data line has as many comma-separated cells as the header, each a decimal number
  (NaN and infinity rejected); blank lines are skipped;
- the time column passes :func:`~msens.io.waveform.check_time`, with the rounding of the
  printed times allowed for: an oscilloscope export with, say, 6 significant digits of a
  10 MHz record is accepted, and its time axis is replaced by the least-squares uniform grid
  (:func:`~msens.io.waveform.uniform_axis`) when the printed values deviate from a uniform grid
  by more than :data:`~msens.io.waveform.TIME_RTOL` dt. Files with full-precision times (as
  the writer makes them) keep their times exactly.

Text is UTF-8 (a byte-order mark is allowed); line ends may be LF or CRLF. The writer
prints floats with ``repr`` (shortest text that reads back to the same float64), so a
write-read round trip is exact.
"""

from __future__ import annotations

import codecs
import csv
import io
import os
from dataclasses import dataclass
from decimal import Decimal

import numpy as np

from msens.errors import InputError
from msens.io._files import atomic_write_bytes, read_bytes
from msens.io.waveform import (
    TIME_NAME,
    TIME_RTOL,
    VERSION,
    VERSION_KEY,
    Channel,
    Waveform,
    check_channels,
    check_metadata_item,
    check_time,
    check_values,
    grid_deviation,
    uniform_axis,
)


def read_csv(path: str | os.PathLike[str]) -> Waveform:
    """Read a waveform CSV file.

    Parameters
    ----------
    path : path-like
        File to read.

    Returns
    -------
    Waveform

    Raises
    ------
    InputError
        On any malformed content, naming the file and line.
    """
    raw = read_bytes(path)
    source = str(path)
    if not raw.isascii():  # ASCII is UTF-8; otherwise check without keeping a decoded copy
        check_utf8(raw, source, bom=True)
    return _parse(raw, source, bom=True)


def parse_csv(text: str, source: str) -> Waveform:
    """Parse waveform CSV ``text``; ``source`` names it in messages (e.g. the path)."""
    return _parse(text.encode("utf-8", "surrogatepass"), source, bom=False)


def check_utf8(raw: bytes, source: str, *, bom: bool) -> None:
    """Raise InputError naming the first byte of ``raw`` that is not UTF-8 (decoded in
    pieces of about a MiB, so no decoded copy of a large file is held)."""
    at = 3 if bom and raw.startswith(codecs.BOM_UTF8) else 0
    step = 1 << 20
    while at < len(raw):
        stop = min(at + step, len(raw))
        while stop < len(raw) and stop > at and raw[stop] & 0xC0 == 0x80:
            stop -= 1  # end the piece on a character boundary
        try:
            raw[at:stop].decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(f"{source}: not UTF-8 text (byte {at + exc.start})") from None
        at = stop


def _parse(raw: bytes, source: str, *, bom: bool) -> Waveform:
    """Parse the bytes of a waveform CSV file (UTF-8, checked by the caller)."""
    start = 3 if bom and raw.startswith(codecs.BOM_UTF8) else 0
    head, body_start = _head_lines(raw, start)
    metadata, header_index = _parse_metadata(head, source)
    if header_index is None:
        raise InputError(
            f"{source}: empty file: no header line (expected '{TIME_NAME},<channel>,...')"
        )
    channels = _parse_header(head[header_index], source, header_index + 1)
    block = read_numeric_block(raw, body_start, header_index + 2, ",", len(channels) + 1)
    if block is None:  # something the fast reader does not vouch for: the line-by-line
        text = raw[start:].decode("utf-8", "surrogatepass")  # reader finds and names it
        lines = [line.removesuffix("\r") for line in text.split("\n")]
        rows, numbers = _parse_rows(lines, header_index + 1, len(channels) + 1, channels,
                                    source)
        table = np.array(rows, dtype=np.float64)
        line_numbers = np.array(numbers, dtype=np.int64)
        resolution = _printed_resolution(lines, numbers)
    else:
        table, line_numbers, resolution = block.values, block.lines, block.resolution

    def locate(i: int) -> str:
        return f"{source}:{line_numbers[i]}"

    time = table[:, 0]
    check_time(time, source, locate, resolution=resolution)
    if grid_deviation(time)[1].max() > TIME_RTOL:
        time = uniform_axis(time)  # printed with too few digits: the rounding is undone
    for j, ch in enumerate(channels):
        check_values(table[:, j + 1], ch.name, source, locate)
    try:
        return Waveform(time, table[:, 1:], channels, metadata)
    except InputError as exc:  # pragma: no cover - the checks above come first
        raise InputError(f"{source}: {exc}") from None


def _head_lines(raw: bytes, start: int) -> tuple[list[str], int]:
    """The lines of ``raw`` up to and including the first that is neither blank nor a ``#``
    line (the header), decoded, and the byte offset just past them."""
    lines: list[str] = []
    at = start
    while at < len(raw):
        end = raw.find(b"\n", at)
        stop = len(raw) if end < 0 else end + 1
        line = raw[at:stop if end < 0 else end].decode("utf-8", "surrogatepass")
        lines.append(line.removesuffix("\r"))
        at = stop
        if lines[-1].strip() and not lines[-1].startswith("#"):
            break
    return lines, at


def _parse_metadata(lines: list[str], source: str) -> tuple[dict[str, str], int | None]:
    """Metadata before the header, and the header's index (None if there is no header)."""
    metadata: dict[str, str] = {}
    version_seen = False
    for index, line in enumerate(lines):
        where = f"{source}:{index + 1}"
        if not line.strip():
            continue
        if not line.startswith("#"):
            return metadata, index
        body = line[1:].strip()
        if not body:
            continue
        key, sep, value = body.partition(":")
        key, value = key.strip(), value.strip()
        if not sep or not key:
            raise InputError(
                f"{where}: bad metadata line {line!r}: lines before the header must be "
                "'# key: value'"
            )
        if key in metadata or (key == VERSION_KEY and version_seen):
            raise InputError(f"{where}: metadata key {key!r} given twice")
        if key == VERSION_KEY:
            if value != VERSION:
                raise InputError(
                    f"{where}: unsupported {VERSION_KEY} version {value!r}; this reader "
                    f"reads version {VERSION}"
                )
            version_seen = True
            continue
        check_metadata_item(key, value, where)
        metadata[key] = value
    return metadata, None


def _parse_header(line: str, source: str, lineno: int) -> tuple[Channel, ...]:
    where = f"{source}:{lineno}"
    cells = [cell.strip() for cell in line.split(",")]
    if cells[0] != TIME_NAME:
        raise InputError(
            f"{where}: no time column: the header's first column must be {TIME_NAME!r}, "
            f"got {cells[0]!r} (an instrument export such as 'Time,CH1,CH2' is read with a "
            "column map: --columns, see README 'Instrument exports')"
        )
    if len(cells) < 2:
        raise InputError(f"{where}: the header names no channel after {TIME_NAME!r}")
    channels = []
    for column, cell in enumerate(cells[1:], start=2):
        try:
            channels.append(Channel.parse(cell))
        except InputError as exc:
            raise InputError(f"{where}: column {column}: {exc}") from None
    check_channels(channels, where)
    return tuple(channels)


def _parse_rows(
    lines: list[str],
    start: int,
    ncol: int,
    channels: tuple[Channel, ...],
    source: str,
) -> tuple[list[list[float]], list[int]]:
    names = (TIME_NAME, *(ch.name for ch in channels))
    rows: list[list[float]] = []
    line_numbers: list[int] = []
    for index in range(start, len(lines)):
        line = lines[index]
        if not line.strip():
            continue
        lineno = index + 1
        if line.startswith("#"):
            raise InputError(
                f"{source}:{lineno}: metadata line after the header; '# key: value' lines "
                "must come before it"
            )
        cells = line.split(",")
        if len(cells) != ncol:
            raise InputError(
                f"{source}:{lineno}: {len(cells)} cells, but the header has {ncol} columns "
                "(unequal lengths)"
            )
        try:
            rows.append([_number(cell) for cell in cells])
        except ValueError:
            column = next(j for j, cell in enumerate(cells) if not _is_number(cell))
            raise InputError(
                f"{source}:{lineno}: column {names[column]!r}: non-numeric cell "
                f"{cells[column].strip()!r}"
            ) from None
        line_numbers.append(lineno)
    if not rows:
        raise InputError(f"{source}: empty file: the header is followed by no data lines")
    return rows, line_numbers


def _printed_resolution(lines: list[str], line_numbers: list[int]) -> float:
    """Rounding of the time column (the first cell of each data line), s; see
    :func:`printed_resolution`."""
    return printed_resolution([lines[i - 1].split(",", 1)[0] for i in line_numbers])


def printed_resolution(cells: list[str]) -> float:
    """Rounding of a fixed-format column of numbers as printed, in its own unit; 0 for any other.

    Instruments print times in a fixed format (e.g. ``-1.00000e-04``: the same number of
    significant digits in every nonzero value, trailing zeros kept); then each value is
    known to half a unit of its last digit, and the largest such half unit is returned.
    Shortest-repr text (msens's own files) has varying digit counts and is exact: 0.
    """
    cells = [Decimal(cell.strip()).as_tuple() for cell in cells]
    # inf/nan (non-int exponents) are rejected later; zeros carry no digit count.
    finite = [c for c in cells if isinstance(c.exponent, int) and any(c.digits)]
    if len(finite) < 3 or len({len(c.digits) for c in finite}) != 1:
        return 0.0
    return 0.5 * 10.0 ** max(int(c.exponent) for c in finite)


@dataclass(frozen=True)
class NumericBlock:
    """Numbers read from the data lines of a delimited text file.

    Attributes
    ----------
    values : ndarray, shape (n, k)
        The requested columns, float64, all finite.
    lines : ndarray of int64, shape (n,)
        1-based line number of each row.
    resolution : float
        Printed rounding of the first requested column (:func:`printed_resolution`; the
        time axis, whose rounding its checks allow for), in its own unit.
    """

    values: np.ndarray
    lines: np.ndarray
    resolution: float


#: Bytes scanned per numpy pass over a file: small, so the temporary masks and offsets
#: stay small next to the file (the peak memory of a large read).
_SCAN_BYTES = 1 << 20


def read_numeric_block(
    raw: bytes,
    start: int,
    first_line: int,
    delimiter: str,
    fields: int,
    columns: list[int] | None = None,
    *,
    exact: bool = True,
    encoding: str = "utf-8",
) -> NumericBlock | None:
    """Read the numbers of the data lines of ``raw`` from byte ``start`` on, fast.

    A compiled parser (``pandas.read_csv``) reads the cells; numpy finds the lines and
    cells in the bytes for the line numbers and the printed resolution. Only a block every
    line of which the line-by-line readers would accept is returned: every non-empty line
    has the right number of fields, every requested cell is a finite number (as ``float``
    reads it: NaN, infinities, digit separators or quotes are not), and line ends are LF or
    CRLF. For anything else the result is None, and the caller reads the lines one by one,
    which finds and names the offending line.

    Parameters
    ----------
    raw : bytes
        The whole file.
    start : int
        Offset of the first data line's first byte.
    first_line : int
        1-based line number of the line at ``start``.
    delimiter : str
        One-character cell separator.
    fields : int
        Fields per line: exactly (``exact``) or at least.
    columns : list of int, optional
        0-based fields to read, in the order wanted (default: all ``fields``).
    exact : bool
        Whether every line must have exactly ``fields`` fields.
    encoding : str
        The text's encoding (cells outside ``columns`` may hold any text).

    Returns
    -------
    NumericBlock or None
    """
    columns = list(range(fields)) if columns is None else list(columns)
    if start >= len(raw) or raw.count(b"\r", start) != raw.count(b"\r\n", start):
        return None  # nothing to read, or a lone CR (the line-by-line reader's business)
    buf = np.frombuffer(raw, dtype=np.uint8)[start:]
    bounds = _cell_bounds(buf, delimiter, fields, columns[0], exact)
    if bounds is None:
        return None
    lo, hi, index = bounds
    values = _parse_numbers(raw, start, lo.size, delimiter, columns, encoding)
    if values is None:
        return None
    resolution = _column_resolution(buf, lo, hi, values[:, 0])
    return NumericBlock(values, index + first_line, resolution)


def _cell_bounds(buf: np.ndarray, delimiter: str, fields: int, column: int, exact: bool
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Where the cells of field ``column`` of each non-empty line of ``buf`` start and end,
    and each such line's 0-based index; None if a line has not ``fields`` fields (exactly,
    or at least). Found in pieces of about :data:`_SCAN_BYTES` that end at a line end."""
    dtype = np.int32 if buf.size < 2**31 - 1 else np.int64
    most = int(np.count_nonzero(buf == 10)) + 1 if buf.size < _SCAN_BYTES else \
        sum(int(np.count_nonzero(buf[i:i + _SCAN_BYTES] == 10))
            for i in range(0, buf.size, _SCAN_BYTES)) + 1
    lo_all, hi_all = np.empty(most, dtype), np.empty(most, dtype)
    index_all = np.empty(most, np.int64)
    at, line0, n = 0, 0, 0
    sep = ord(delimiter)
    while at < buf.size:
        stop = at + _SCAN_BYTES
        if stop < buf.size:
            found = np.flatnonzero(buf[stop:stop + (1 << 16)] == 10)
            stop = stop + int(found[0]) + 1 if found.size else buf.size
        piece = buf[at:stop]
        newlines = np.flatnonzero(piece == 10).astype(dtype)
        begins = np.concatenate((np.zeros(1, dtype), newlines + 1))
        ends = np.concatenate((newlines, np.full(1, piece.size, dtype)))
        if stop < buf.size:  # the piece ends with a newline: no line after it
            begins, ends = begins[:-1], ends[:-1]
        ends -= (ends > begins) & (piece[np.maximum(ends - 1, 0)] == 13)  # CRLF
        keep = np.flatnonzero(ends > begins)  # empty lines are skipped
        begins, ends = begins[keep], ends[keep]
        seps = np.flatnonzero(piece == sep).astype(dtype)
        first = np.searchsorted(seps, begins)
        count = np.searchsorted(seps, ends)
        count -= first - 1  # fields per line
        if (np.any(count != fields) if exact else np.any(count < fields)):
            return None
        last = max(seps.size - 1, 0)
        lo = begins if column == 0 else seps[np.minimum(first + column - 1, last)] + 1
        hi = np.where(count > column + 1, seps[np.minimum(first + column, last)], ends) \
            if seps.size else ends
        m = keep.size
        lo_all[n:n + m] = lo + at
        hi_all[n:n + m] = hi + at
        index_all[n:n + m] = keep + line0
        n += m
        line0 += newlines.size
        at = stop
    if n == 0:
        return None
    return lo_all[:n], hi_all[:n], index_all[:n]


#: Rows per piece handed to the compiled parser (its word buffers grow with the piece).
_PARSE_ROWS = 1 << 16


def _parse_numbers(raw: bytes, start: int, rows: int, delimiter: str, columns: list[int],
                   encoding: str) -> np.ndarray | None:
    """The ``columns`` of the ``rows`` non-empty lines of ``raw`` from ``start`` on, shape
    (rows, len(columns)), all finite; None for anything else (a cell that is not a number,
    NaN or infinity, a ragged line, another row count)."""
    import pandas as pd

    handle = io.BytesIO(raw)
    handle.seek(start)
    # exact floats: pandas 3 parses them exactly; pandas 2 only with its round-trip parser
    options = {"float_precision": "round_trip"} if pd.__version__.startswith("2.") else {}
    order = sorted(set(columns))
    take = [order.index(k) for k in columns]
    values = np.empty((rows, len(columns)))
    done = 0
    try:
        with pd.read_csv(handle, sep=delimiter, header=None, usecols=order, dtype=np.float64,
                         quoting=csv.QUOTE_NONE, engine="c", encoding=encoding,
                         skip_blank_lines=True, chunksize=_PARSE_ROWS, **options) as reader:
            for frame in reader:
                if list(frame.columns) != order or done + len(frame) > rows:
                    return None
                piece = frame.to_numpy(dtype=np.float64, copy=False)[:, take]
                if not np.isfinite(piece).all():
                    return None  # NaN or infinity: the line-by-line reader names the line
                values[done:done + len(frame)] = piece
                done += len(frame)
    except (ValueError, TypeError, OverflowError, UnicodeDecodeError, pd.errors.ParserError):
        return None  # a cell that is not a number, or a ragged line
    return values if done == rows else None


def _positions(buf: np.ndarray, byte: int) -> np.ndarray:
    """Offsets of ``byte`` in ``buf``, found in pieces of :data:`_SCAN_BYTES` (int32 below
    2 GiB: half the memory of int64 for a file of a million lines)."""
    dtype = np.int32 if buf.size < 2**31 - 1 else np.int64
    parts = [(np.flatnonzero(buf[at:at + _SCAN_BYTES] == byte) + at).astype(dtype)
             for at in range(0, buf.size, _SCAN_BYTES)]
    return np.concatenate(parts) if parts else np.empty(0, dtype)


def _column_resolution(buf: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                       values: np.ndarray) -> float:
    """:func:`printed_resolution` of the cells ``buf[lo[i]:hi[i]]`` whose numbers are
    ``values`` (shape (n,)), vectorised over the cells in pieces.

    A cell's last digit has the exponent X = (its exponent) - (digits after the point); its
    significant digits are those of the integer ``|value| / 10**X``. Cells beyond what that
    computes exactly (huge exponents, 14 or more digits, long cells) go to
    :func:`printed_resolution`.
    """
    counts: set[int] = set()
    live = 0
    top = None
    long_numbers = False
    step = _PARSE_ROWS // 4
    for at in range(0, lo.size, step):
        piece = _digit_counts(buf, lo[at:at + step], hi[at:at + step], values[at:at + step])
        if piece is None:
            return _slow_resolution(buf, lo, hi)
        digits, n_live, exponent, inexact = piece
        counts.update(digits)
        live += n_live
        long_numbers |= inexact
        if exponent is not None:
            top = exponent if top is None else max(top, exponent)
        if len(counts) > 1:
            return 0.0  # e.g. shortest-repr numbers
    if live < 3 or top is None:
        return 0.0
    if long_numbers:  # 14 digits or more somewhere
        return 0.0 if counts and max(counts) < 14 else _slow_resolution(buf, lo, hi)
    return 0.5 * 10.0 ** top


def _digit_counts(buf: np.ndarray, lo: np.ndarray, hi: np.ndarray, values: np.ndarray
                  ) -> tuple[set[int], int, int | None, bool] | None:
    """For the nonzero cells ``buf[lo[i]:hi[i]]`` (numbers ``values``): the set of their
    significant digit counts (of those below 14 digits), how many there are, the largest
    exponent of a last digit, and whether any has 14 digits or more; None where only
    :func:`printed_resolution` can tell."""
    n = lo.size
    for _ in range(8):  # trailing blanks are not digits
        blank = (hi > lo) & np.isin(buf[np.maximum(hi - 1, 0)], (9, 11, 12, 32))
        if not blank.any():
            break
        hi = hi - blank
    size = hi - lo
    width = int(size.max(initial=0))
    if width > 40 or blank.any():
        return None
    dot_at = np.full(n, -1, dtype=np.int32)  # offsets within the cell
    e_at = np.full(n, -1, dtype=np.int32)
    top = buf.size - 1
    for j in range(width):
        ch = buf[np.minimum(lo + j, top)]
        inside = j < size
        dot_at[(dot_at < 0) & inside & (ch == 46)] = j
        e_at[(e_at < 0) & inside & ((ch == 101) | (ch == 69))] = j
    has_e = e_at >= 0
    mant_end = np.where(has_e, e_at, size)
    frac = np.where((dot_at >= 0) & (dot_at < mant_end), mant_end - dot_at - 1, 0)
    tail = np.where(has_e, size - e_at - 1, 0)  # the exponent's text after the e
    if tail.max(initial=0) > 6:
        return None
    ev = np.zeros(n, dtype=np.int64)
    negative = np.zeros(n, dtype=bool)
    for j in range(1, int(tail.max(initial=0)) + 1):
        inside = j <= tail
        ch = buf[np.where(inside, lo + e_at + j, 0)].astype(np.int64)
        digit = inside & (ch >= 48) & (ch <= 57)
        ev = np.where(digit, ev * 10 + ch - 48, ev)
        negative |= inside & (ch == 45)
    exponent = np.where(negative, -ev, ev) - frac
    if np.abs(exponent).max(initial=0) > 290:
        return None
    coefficient = np.rint(np.abs(values) * 10.0 ** (-exponent.astype(np.float64)))
    live = coefficient > 0  # zeros carry no digit count
    exact = coefficient < 1e14  # below, the float division gives the integer exactly
    digits = np.floor(np.log10(coefficient[live & exact])).astype(np.int64) + 1
    n_live = int(live.sum())
    return (set(np.unique(digits).tolist()), n_live,
            int(exponent[live].max()) if n_live else None, bool((live & ~exact).any()))


def _slow_resolution(buf: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """:func:`printed_resolution` of the cells ``buf[lo[i]:hi[i]]``, one by one."""
    cells = [bytes(buf[a:b]).decode("latin-1") for a, b in zip(lo, hi, strict=True)]
    return printed_resolution(cells)


def _number(cell: str) -> float:
    # float() also takes '1_000'; a CSV number has no digit separators.
    if "_" in cell:
        raise ValueError(cell)
    return float(cell)


def _is_number(cell: str) -> bool:
    try:
        _number(cell)
    except ValueError:
        return False
    return True


def format_csv(waveform: Waveform) -> str:
    """CSV text of ``waveform`` (version line, metadata, header, repr-exact rows)."""
    out = [f"# {VERSION_KEY}: {VERSION}"]
    out += [
        f"# {key}: {value}" if value else f"# {key}:" for key, value in waveform.metadata.items()
    ]
    out.append(",".join((TIME_NAME, *waveform.names)))
    table = np.column_stack((waveform.time, waveform.data)).tolist()
    out += [",".join(map(repr, row)) for row in table]
    return "\n".join(out) + "\n"


def write_csv(waveform: Waveform, path: str | os.PathLike[str], *, overwrite: bool = False) -> None:
    """Write ``waveform`` to a CSV file atomically; never replaces a file unless asked.

    Raises
    ------
    InputError
        If ``path`` exists and ``overwrite`` is false.
    """
    atomic_write_bytes(path, format_csv(waveform).encode("utf-8"), overwrite)
