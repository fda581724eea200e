"""One msens command at a time per output folder: an advisory lock file.

Two commands writing into one folder would interleave their files and their manifest; the
second is refused at once, saying plainly that the folder is in use. The lock is an
``flock`` on :data:`LOCK_NAME`, which the kernel releases when the holder exits in any way
(SIGKILL included), so a killed run never leaves a stale lock behind.
"""

from __future__ import annotations

import os
from pathlib import Path

from msens.errors import InputError

try:
    import fcntl
except ImportError:  # pragma: no cover - not on POSIX: no locking
    fcntl = None  # type: ignore[assignment]

#: Name of the lock file in an output folder.
LOCK_NAME = ".msens-lock"

#: Locks this process holds: real path of the folder -> [file descriptor, users].
_held: dict[str, list[int]] = {}


def acquire(directory: str | os.PathLike[str]) -> str:
    """Lock ``directory`` for this process (again, if it holds it already).

    Returns
    -------
    str
        The key to give :func:`release`.

    Raises
    ------
    InputError
        Another process holds the folder.
    """
    key = os.path.realpath(directory)
    if key in _held:
        _held[key][1] += 1
        return key
    if fcntl is None:  # pragma: no cover
        _held[key] = [-1, 1]
        return key
    path = Path(key) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        raise InputError(f"--out '{directory}': cannot create its lock file {LOCK_NAME} "
                         f"({exc.strerror or exc})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise InputError(f"--out '{directory}' is in use by another msens command (process "
                         f"{holder}); wait for it to finish or choose another --out "
                         "directory") from None
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
    except OSError as exc:  # a full disk: nothing else would be written there either
        os.close(fd)
        raise InputError(f"--out '{directory}': cannot write its lock file {LOCK_NAME} "
                         f"({exc.strerror or exc})") from None
    _held[key] = [fd, 1]
    return key


def release(key: str) -> None:
    """Undo one :func:`acquire`; the lock is dropped when its last user releases it."""
    entry = _held.get(key)
    if entry is None:
        return
    entry[1] -= 1
    if entry[1] <= 0:
        del _held[key]
        if entry[0] >= 0:
            os.close(entry[0])  # closing the descriptor releases the flock


def release_all() -> None:
    """Drop every lock this process holds (the end of a command)."""
    for key in list(_held):
        _held[key][1] = 0
        release(key)
