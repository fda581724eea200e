"""File plumbing shared by the waveform formats: checked reads and atomic writes."""

from __future__ import annotations

import os
from pathlib import Path

from msens.errors import InputError
from msens.io.atomic import atomic_write_bytes as _atomic_bytes


def read_bytes(path: str | os.PathLike[str]) -> bytes:
    """Whole content of ``path``; InputError if it is missing or unreadable."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: file not found")
    if not p.is_file():
        raise InputError(f"{p}: not a regular file")
    try:
        return p.read_bytes()
    except OSError as exc:
        raise InputError(f"{p}: cannot read ({exc.strerror or exc})") from None


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
