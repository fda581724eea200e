"""File plumbing shared by the waveform formats: checked reads and atomic writes."""

from __future__ import annotations

import os
from pathlib import Path

from msens.errors import InputError, shorten
from msens.io.atomic import atomic_write_bytes as _atomic_bytes

#: Largest waveform file msens reads, bytes (a 1 ms record of 8 channels at 10 MHz as CSV
#: is about 2 MB; a larger file is a mistake or would not fit in memory once parsed).
MAX_DATA_BYTES = 1 << 30
#: Largest study, sweep or column-map file msens reads, bytes (the shipped studies are a
#: few kB; tabulated B-H curves add a few kB more).
MAX_TEXT_BYTES = 4 << 20


def check_path(value: object, what: str = "file") -> Path:
    """``value`` as a :class:`~pathlib.Path` if it is a non-empty ``str`` or path-like,
    else InputError naming what was given (``compare(study, 3)``, ``load(None)``)."""
    if not isinstance(value, str | os.PathLike):
        raise InputError(f"{what} must be a path (str or pathlib.Path), got "
                         f"{type(value).__name__} {shorten(value)}")
    text = os.fspath(value)
    if not isinstance(text, str):
        raise InputError(f"{what} must be a text path, got {shorten(text)}")
    if text.strip() == "":
        raise InputError(f"{what} path is empty")
    if "\0" in text:
        raise InputError(f"{what} path {shorten(text)} holds a NUL character")
    try:
        os.stat(text)
    except (FileNotFoundError, NotADirectoryError):
        pass  # a new name in a folder that exists or will be made: the caller's business
    except OSError as exc:  # a name too long, a loop of links, no permission to look
        raise InputError(f"{what} {shorten(text)}: {exc.strerror or exc}") from None
    except ValueError as exc:  # e.g. characters the OS cannot encode
        raise InputError(f"{what} {shorten(text)}: {exc}") from None
    return Path(text)


def read_bytes(path: str | os.PathLike[str], *, limit: int = MAX_DATA_BYTES,
               what: str = "file") -> bytes:
    """Whole content of the regular file ``path``.

    Devices, pipes and folders are refused (``/dev/zero`` would be read forever), and so is
    a file larger than ``limit`` bytes (checked while reading, so a file that grows is also
    bounded).

    Parameters
    ----------
    path : path-like
        File to read.
    limit : int
        Largest size accepted, bytes.
    what : str
        What the file is, for messages ("study file", "waveform file").

    Raises
    ------
    InputError
        Missing, not a regular file, too large, or unreadable (naming the path and reason).
    """
    p = check_path(path, what)
    if not p.exists():
        raise InputError(f"{p}: {what} not found")
    if not p.is_file():
        kind = "a folder" if p.is_dir() else "a device, pipe or socket"
        raise InputError(f"{p}: not a regular file ({kind}); give a {what} msens can read")
    try:
        with open(p, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise InputError(f"{p}: cannot read ({exc.strerror or exc})") from None
    if len(data) > limit:
        raise InputError(f"{p}: {what} larger than {limit / 2**20:g} MiB; msens reads at most "
                         "that much (is it the right file?)")
    return data


def read_text(path: str | os.PathLike[str], *, what: str,
              limit: int = MAX_TEXT_BYTES) -> str:
    """:func:`read_bytes` of a UTF-8 text file (a leading byte-order mark kept)."""
    raw = read_bytes(path, limit=limit, what=what)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: {what} is not UTF-8 text (byte {exc.start}: "
                         f"{shorten(raw[exc.start:exc.start + 4])})") from None


def atomic_write_bytes(path: str | os.PathLike[str], content: bytes, overwrite: bool) -> Path:
    """Write ``content`` to ``path`` atomically (:func:`msens.io.atomic.atomic_write`).

    With ``overwrite=False`` an existing file is never replaced.

    Raises
    ------
    InputError
        If the file exists and ``overwrite`` is false, or the folder does not exist.
    """
    p = Path(path)
    if not p.parent.is_dir():
        raise InputError(f"{p}: folder {p.parent} does not exist")
    if p.exists() and not overwrite:
        raise InputError(f"{p}: file exists; pass overwrite=True to replace it")
    return _atomic_bytes(p, content, overwrite=overwrite)
