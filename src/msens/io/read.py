"""Read and write waveforms in any supported format, chosen by the file suffix.

============  ===========================================
suffix        format
============  ===========================================
``.csv``      :mod:`msens.io.csv` (design.md §8)
``.npz``      :mod:`msens.io.npz`
``.tdms``     :mod:`msens.io.tdms` (LabVIEW, via npTDMS)
============  ===========================================

An instrument's own text export (``Time,CH1,CH2``) is read through a column map
(:mod:`msens.io.columns`): pass ``columns=`` or a :class:`~msens.io.mapped.MappedFile`.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from msens.errors import InputError, shorten
from msens.io._files import check_path
from msens.io.columns import ColumnMap
from msens.io.csv import read_csv, write_csv
from msens.io.mapped import MappedFile, read_mapped
from msens.io.npz import read_npz, write_npz
from msens.io.tdms import read_tdms, write_tdms
from msens.io.waveform import Waveform

_READERS: dict[str, Callable[[Path], Waveform]] = {
    ".csv": read_csv,
    ".npz": read_npz,
    ".tdms": read_tdms,
}
_WRITERS: dict[str, Callable[..., None]] = {
    ".csv": write_csv,
    ".npz": write_npz,
    ".tdms": write_tdms,
}
SUFFIXES: tuple[str, ...] = tuple(_READERS)


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in _READERS:
        raise InputError(
            f"{path}: unknown waveform file type {path.suffix!r}; allowed suffixes are "
            f"{', '.join(SUFFIXES)}"
        )
    return suffix


def read_waveform(path: str | os.PathLike[str],
                  columns: str | os.PathLike[str] | ColumnMap | None = None) -> Waveform:
    """Read a measured waveform from a ``.csv``, ``.npz`` or ``.tdms`` file.

    Parameters
    ----------
    path : path-like
        File to read; the (case-insensitive) suffix selects the format. A
        :class:`~msens.io.mapped.MappedFile` is read through its column map.
    columns : str, path-like or ColumnMap, optional
        Column map of an instrument's text export (inline ``time=Time:ms,bead@13=CH1:mV``
        or a ``.toml`` file; :mod:`msens.io.columns`); the file is then read as that export.

    Returns
    -------
    Waveform

    Raises
    ------
    InputError
        For an unknown suffix, a missing file or malformed content, naming the file
        (and line or channel), or a bad column map, naming its item.
    """
    if isinstance(path, MappedFile):
        return read_mapped(path.path, path.columns if columns is None else columns)
    p = check_path(path, "waveform file")
    if columns is not None:
        return read_mapped(p, columns)
    return _READERS[_suffix(p)](p)


def write_waveform(
    waveform: Waveform, path: str | os.PathLike[str], *, overwrite: bool = False
) -> Path:
    """Write ``waveform`` atomically in the format given by the suffix of ``path``.

    Parameters
    ----------
    waveform : Waveform
    path : path-like
        Target; ``.csv``, ``.npz`` or ``.tdms``.
    overwrite : bool
        Replace an existing file; by default an existing file is never touched.

    Returns
    -------
    Path
        The written path.

    Raises
    ------
    InputError
        For something that is not a :class:`Waveform`, an unknown suffix, a missing
        folder, or an existing file without ``overwrite``.
    """
    if not isinstance(waveform, Waveform):
        raise InputError(f"write_waveform needs a Waveform (msens.Waveform or "
                         f"msens.read_waveform), got {type(waveform).__name__} "
                         f"{shorten(waveform)}")
    p = check_path(path, "waveform file")
    _WRITERS[_suffix(p)](waveform, p, overwrite=overwrite)
    return p


def check_waveform_file(path: str | os.PathLike[str],
                        columns: str | os.PathLike[str] | ColumnMap | None = None) -> Waveform:
    """Read and fully validate a waveform file (through ``columns``, a column map, if given);
    the waveform if valid, else InputError."""
    return read_waveform(path, columns)


def describe(waveform: Waveform) -> str:
    """One-line summary: samples, dt, time span and channels."""
    return (
        f"{waveform.time.size} samples, dt = {waveform.dt:.6g} s, "
        f"t = {waveform.time[0]:.6g} .. {waveform.time[-1]:.6g} s, "
        f"channels: {', '.join(waveform.names)}"
    )


def main_check(argv: Sequence[str], columns: ColumnMap | None = None) -> int:
    """Console entry: check waveform files; 0 if all are valid, 2 otherwise.

    Prints ``<path>: ok, <summary>`` on stdout for each valid file and the error message
    on stderr for each invalid one (no traceback). ``columns`` is the column map every
    file is read through, if any.
    """
    if not argv:
        print("usage: msens check-waveform FILE [FILE ...]", file=sys.stderr)
        return 2
    status = 0
    for arg in argv:
        try:
            waveform = check_waveform_file(arg, columns)
        except InputError as exc:
            print(f"msens: error: {exc}", file=sys.stderr)
            status = 2
        else:
            print(f"{arg}: ok, {describe(waveform)}")
    return status
