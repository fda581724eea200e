"""Numba's on-disk cache for the chain kernel, invalidated by an edit to any of its files.

Why: numba stamps each cached function with a hash of the one file that defines it. The
compiled code of a kernel function also holds every function it calls (linked or inlined)
and every global constant it reads, frozen at compile time, from the other files of this
package. After an edit there, numba would load the stale code of the unchanged callers. So
every function cached from a file of this package carries a stamp of *all* its source files
(:func:`package_digest`): an edit to any of them makes every cached kernel function compile
afresh on its next call.

The kernel compiles only from files of this package (numpy and numba aside; a test walks its
call graph and imports to check), so the stamp covers everything it is compiled from.

How: a numba cache locator (the object that tells numba where a function's cache lives and
how fresh its source is) is put in front of numba's own. For functions defined in this
package it wraps the locator numba would have chosen (same folder, so ``NUMBA_CACHE_DIR`` is
honoured) and replaces the source stamp; for every other function it declines, leaving
numba's choice unchanged. With ``NUMBA_CACHE_LOCATOR_CLASSES`` set numba ignores the
locator list, so the guard cannot act: a warning says so.

Where: in the user cache folder (:func:`msens.numba_cache.use_user_cache`, unless
``NUMBA_CACHE_DIR`` is set), so the compiled kernel survives reinstalling msens: the stamp
is the files' content, and a reinstall puts them at the same path. Each compiled variant has
its own data file there (:mod:`msens.numba_cache_file`), so processes compiling at once
cannot mix them up.
"""

from __future__ import annotations

import functools
import hashlib
import warnings
from pathlib import Path

import numba
from numba.core import caching

import msens.numba_cache_file  # noqa: F401 (user cache folder; one file per variant)

#: The folder whose ``*.py`` files the kernel is compiled from.
PACKAGE_DIR = Path(__file__).resolve().parent

# numba >= 0.61 names the class CacheImpl, earlier versions _CacheImpl.
_CACHE_IMPL = getattr(caching, "CacheImpl", None) or caching._CacheImpl


def package_digest(folder: Path = PACKAGE_DIR) -> str:
    """SHA-256 over the names and contents of the ``*.py`` files in ``folder``.

    Parameters
    ----------
    folder : Path
        Default: this package.

    Returns
    -------
    str
        64 hex digits; changes with any edit, addition, removal or renaming of a file.
    """
    files = sorted(Path(folder).resolve().glob("*.py"))
    return _digest(tuple((f, f.stat().st_mtime_ns, f.stat().st_size) for f in files))


@functools.cache
def _digest(files: tuple[tuple[Path, int, int], ...]) -> str:
    # Keyed by modification time and size, as numba's own stamp: each function decorated
    # at import asks, the files are read once while unchanged.
    h = hashlib.sha256()
    for path, _, _ in files:
        for part in (path.name.encode(), path.read_bytes()):
            h.update(len(part).to_bytes(8, "little"))
            h.update(part)
    return h.hexdigest()


class PackageStampLocator(caching._CacheLocator):
    """numba's chosen cache locator for a function of this package, stamped with
    :func:`package_digest` instead of the hash of the function's own file."""

    def __init__(self, inner: caching._CacheLocator) -> None:
        self._inner = inner

    def ensure_cache_path(self):
        self._inner.ensure_cache_path()

    def get_cache_path(self):
        return self._inner.get_cache_path()

    def get_disambiguator(self):
        return self._inner.get_disambiguator()

    def get_source_stamp(self):
        return ("msens.chain.kernel", package_digest())

    @classmethod
    def from_function(cls, py_func, py_file):
        if Path(py_file).resolve().parent != PACKAGE_DIR:
            return None
        for other in _CACHE_IMPL._locator_classes:
            if other is not cls:
                inner = other.from_function(py_func, py_file)
                if inner is not None:
                    return cls(inner)
        return None


def install() -> None:
    """Put :class:`PackageStampLocator` first in numba's locator list (idempotent)."""
    classes = _CACHE_IMPL._locator_classes
    if PackageStampLocator not in classes:
        classes.insert(0, PackageStampLocator)
    if getattr(numba.config, "CACHE_LOCATOR_CLASSES", ""):
        warnings.warn("NUMBA_CACHE_LOCATOR_CLASSES is set: numba then ignores the chain "
                      "kernel's cache guard, and an edit to one kernel file may leave stale "
                      "compiled code of the others in the cache", stacklevel=2)


install()
