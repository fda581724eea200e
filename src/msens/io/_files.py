"""File plumbing shared by the waveform formats: checked reads and atomic writes."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from msens.errors import InputError


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
    """Write ``content`` to ``path`` atomically: temp file in the same folder, then rename.

    With ``overwrite=False`` an existing file is never replaced (the final step is a
    hard link, which fails atomically if the name exists; where hard links are not
    supported, an existence check followed by a rename).

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
    fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{p.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(content)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)  # mkstemp makes 0600: give the file the usual permissions
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        if overwrite:
            os.replace(tmp, p)
        else:
            _link_new(tmp, p)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return p


def _link_new(tmp: str, path: Path) -> None:
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise InputError(f"{path}: file exists; pass overwrite=True to replace it") from None
    except OSError:
        # No hard links here (some network/FAT file systems): check, then rename.
        if path.exists():
            raise InputError(f"{path}: file exists; pass overwrite=True to replace it") from None
        os.replace(tmp, path)
