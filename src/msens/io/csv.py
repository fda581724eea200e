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

import os
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
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    return parse_csv(text, str(path))


def parse_csv(text: str, source: str) -> Waveform:
    """Parse waveform CSV ``text``; ``source`` names it in messages (e.g. the path)."""
    # Split on LF only: str.splitlines also breaks on form feeds and the like, which would
    # shift the line numbers in messages away from what an editor shows.
    lines = [line.removesuffix("\r") for line in text.split("\n")]
    metadata, header_index = _parse_metadata(lines, source)
    if header_index is None:
        raise InputError(
            f"{source}: empty file: no header line (expected '{TIME_NAME},<channel>,...')"
        )
    channels = _parse_header(lines[header_index], source, header_index + 1)
    rows, line_numbers = _parse_rows(lines, header_index + 1, len(channels) + 1, channels, source)

    def locate(i: int) -> str:
        return f"{source}:{line_numbers[i]}"

    table = np.array(rows, dtype=np.float64)
    time = table[:, 0]
    check_time(time, source, locate, resolution=_printed_resolution(lines, line_numbers))
    if grid_deviation(time)[1].max() > TIME_RTOL:
        time = uniform_axis(time)  # printed with too few digits: the rounding is undone
    for j, ch in enumerate(channels):
        check_values(table[:, j + 1], ch.name, source, locate)
    try:
        return Waveform(time, table[:, 1:], channels, metadata)
    except InputError as exc:  # pragma: no cover - the checks above come first
        raise InputError(f"{source}: {exc}") from None


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
