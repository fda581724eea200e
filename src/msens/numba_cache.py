"""Where numba keeps msens's compiled code: the user cache folder, so it survives reinstalling.

numba caches a compiled function next to its source (``__pycache__``) unless
``NUMBA_CACHE_DIR`` names a folder. For an installed msens the source lives in
``site-packages``, which ``pip install`` replaces: the chain kernel (about
:data:`msens.progress.KERNEL_COMPILE_S` seconds to compile) would be compiled again after
every reinstall. :func:`use_user_cache` points numba at a folder in the user's cache
instead (unless the user has set ``NUMBA_CACHE_DIR``); the chain kernel's cache guard
(:mod:`msens.chain.kernel.cache_guard`) keys its entries by the content of the kernel's
files, not their paths or times, so a reinstall of the same msens finds them.

Standard library only: the command line calls it before numba is imported.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

#: The environment variable numba reads; a value the user set is never changed.
CACHE_ENV = "NUMBA_CACHE_DIR"


def default_dir() -> Path:
    """The user cache folder for msens's compiled code.

    ``$XDG_CACHE_HOME/msens/numba`` (default ``~/.cache/msens/numba``) on Linux,
    ``~/Library/Caches/msens/numba`` on macOS, ``%LOCALAPPDATA%\\msens\\numba`` on Windows.
    """
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "msens" / "numba"


def use_user_cache() -> Path | None:
    """Set ``NUMBA_CACHE_DIR`` to :func:`default_dir` unless it is set; the folder in use.

    Sets the environment (worker processes inherit it) and, if numba is already imported,
    its configuration (numba reads it when a cached function is defined). Returns None when
    the folder cannot be created (numba then caches next to the sources, as by default).
    """
    given = os.environ.get(CACHE_ENV)
    if given:
        return Path(given)
    path = default_dir()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    os.environ[CACHE_ENV] = str(path)
    numba = sys.modules.get("numba")
    if numba is not None:
        numba.config.CACHE_DIR = str(path)
    return path
