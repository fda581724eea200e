"""The one way msens writes a file: atomically, durably, with the usual permissions.

Every result, cache entry, mesh and waveform goes through :func:`atomic_write`: the content
is written to a temporary file in the target's folder, flushed to disk (fsync), given the
permissions a new file gets under the umask (``mkstemp`` makes 0600), and renamed onto the
target, so a reader sees the old file or the new one, never half of one, even after a crash
or SIGKILL. A temporary file left by a killed process is recognisable by its name
(:data:`TEMP_MARK` and the writer's process id) and removed by :func:`clean_stale` on the next
run in that folder.
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

from msens.errors import InputError

#: Part of every temporary file's name: ``.<name>.<pid>.<random>.msens-tmp<suffix>``.
TEMP_MARK = ".msens-tmp"
_TEMP_RE = re.compile(r"^\..+\.(\d+)\.[^.]+" + re.escape(TEMP_MARK) + r"(\.[^.]*)?$")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _fsync_dir(directory: Path) -> None:
    """Make a rename in ``directory`` durable (not supported everywhere: best effort)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write(path: str | os.PathLike[str], write: Callable[[Path], None], *,
                 overwrite: bool = True) -> Path:
    """Write ``path`` atomically through ``write(tmp_path)``.

    Parameters
    ----------
    path : str or PathLike
        Target file; its folder is created if missing.
    write : callable
        Writes the content to the temporary file it is given (which has ``path``'s suffix,
        for writers that choose the format by it).
    overwrite : bool
        False: never replace an existing file (the final step is a hard link, which fails
        if the name exists; where hard links are not supported, a check then a rename).

    Returns
    -------
    Path

    Raises
    ------
    InputError
        ``overwrite`` is False and ``path`` exists, or the file cannot be written (full
        disk, read-only file system, no permission, a path under ``/proc``...): one message
        naming ``path`` and the reason. No partial file is left.
    """
    p = Path(path)
    try:
        return _atomic_write(p, write, overwrite)
    except InputError:
        raise
    except OSError as exc:  # full disk, read-only file system, no permission, /proc, ...
        # one message naming the path and the reason, whichever step failed
        raise InputError(f"{p}: cannot write ({exc.strerror or type(exc).__name__}); nothing "
                         "was written there (an existing file is unchanged)") from None


def _atomic_write(p: Path, write: Callable[[Path], None], overwrite: bool) -> Path:
    """:func:`atomic_write` without the mapping of OS errors."""
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{p}: folder {p.parent} cannot be created ({exc.strerror or exc})"
                         ) from None
    if not overwrite and p.exists():
        raise InputError(f"{p}: file exists; msens never overwrites a file it did not write")
    fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{p.name}.{os.getpid()}.",
                               suffix=TEMP_MARK + p.suffix)
    os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb+") as fh:  # the writer may have closed (or replaced) the file
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        if overwrite:
            os.replace(tmp, p)
        else:
            _link_new(tmp, p)
        _fsync_dir(p.parent)
    finally:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        except OSError:  # pragma: no cover - a folder that became read-only meanwhile
            pass
    return p


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes, *,
                       overwrite: bool = True) -> Path:
    """:func:`atomic_write` of ``data``."""
    return atomic_write(path, lambda t: t.write_bytes(data), overwrite=overwrite)


def atomic_write_text(path: str | os.PathLike[str], text: str, *,
                      overwrite: bool = True) -> Path:
    """:func:`atomic_write` of ``text`` (UTF-8)."""
    return atomic_write(path, lambda t: t.write_text(text, encoding="utf-8"),
                        overwrite=overwrite)


def _link_new(tmp: str, path: Path) -> None:
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise InputError(f"{path}: file exists; msens never overwrites a file it did not "
                         "write") from None
    except OSError:
        # no hard links here (some network and FAT file systems): check, then rename
        if path.exists():
            raise InputError(f"{path}: file exists; msens never overwrites a file it did "
                             "not write") from None
        os.replace(tmp, path)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, owned by someone else
        return True
    return True


def clean_stale(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files of writers that are no longer running from ``directory``.

    Only names made by :func:`atomic_write` whose process id is not alive are removed, so a
    concurrent writer's file is left alone.

    Returns
    -------
    list of Path
        The files removed.
    """
    d = Path(directory)
    removed = []
    try:
        entries = list(d.iterdir())
    except OSError:
        return removed
    for entry in entries:
        m = _TEMP_RE.match(entry.name)
        if m is None or _alive(int(m.group(1))):
            continue
        try:
            entry.unlink()
            removed.append(entry)
        except OSError:
            pass
    return removed
