"""Where numba keeps msens's compiled code: the user cache folder, so it survives reinstalling.

numba caches a compiled function next to its source (``__pycache__``) unless
``NUMBA_CACHE_DIR`` names a folder. For an installed msens the source lives in
``site-packages``, which ``pip install`` replaces: the chain kernel (about
:data:`msens.progress.KERNEL_COMPILE_S` seconds to compile) would be compiled again after
every reinstall. :func:`use_user_cache` points numba at a folder in the user's cache
instead (unless the user has set ``NUMBA_CACHE_DIR``); the chain kernel's cache guard
(:mod:`msens.chain.kernel.cache_guard`) keys its entries by the content of the kernel's
files, not their paths or times, so a reinstall of the same msens finds them.

:func:`compile_in_background` compiles numba code into that folder in a second Python
process, while this one does other work (``msens run`` compiles the chain kernel so on a
first run: :mod:`msens.chain.warmup`).

Standard library only: the command line calls it before numba is imported.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

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


#: Run in the second process: import the parent's msens (its folder first on the path only
#: when another msens, or none, would be found: never the whole site-packages ahead of the
#: standard library), exit as soon as its standard input closes (the parent ended, however
#: it ended), then import the module and call its ``main`` with the arguments.
_CHILD = """
import importlib.util, os, sys
here = sys.argv.pop(1)
spec = importlib.util.find_spec("msens")
if spec is None or os.path.realpath(os.path.dirname(os.path.dirname(spec.origin))) != here:
    sys.path.insert(0, here)
from msens.numba_cache import run_child
sys.exit(run_child(sys.argv[1:]))
"""


@dataclass
class BackgroundCompile:
    """A second Python process compiling numba code into the cache
    (:func:`compile_in_background`).

    It ends by itself when done, or as soon as this process ends (its standard input, a pipe
    from this process, closes); :meth:`stop` ends it earlier.
    """

    process: subprocess.Popen
    errors: IO[bytes]
    #: The lines the process has written to its standard output so far (stages done).
    said: list[str] = field(default_factory=list)

    def running(self) -> bool:
        """Whether the process is still compiling."""
        return self.process.poll() is None

    def wait_for(self, line: str) -> str | None:
        """Wait until the process writes ``line`` to its standard output (a stage done) or
        ends; None if it wrote the line, else what went wrong (:meth:`wait`)."""
        if line in self.said:
            return None
        for got in self.process.stdout:
            self.said.append(got.decode(errors="replace").strip())
            if self.said[-1] == line:
                return None
        return self.wait() or f"it ended without saying {line!r}"

    def wait(self) -> str | None:
        """Wait until the process ends; None if it succeeded, else what went wrong (its exit
        status and the last line it wrote to stderr)."""
        if self.process.stdout is not None and not self.process.stdout.closed:
            rest = self.process.stdout.read().decode(errors="replace")
            self.said.extend(line.strip() for line in rest.splitlines())
        status = self.process.wait()
        lines = []
        if status != 0 and not self.errors.closed:
            self.errors.seek(0)
            lines = self.errors.read().decode(errors="replace").strip().splitlines()
        self._close()
        if status == 0:
            return None
        return f"exit status {status}" + (f": {lines[-1][:300]}" if lines else "")

    def stop(self) -> None:
        """End the process now if it still runs (a half-written cache entry is never read:
        numba writes each file whole under a temporary name, then renames it)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._close()

    def _close(self) -> None:
        for pipe in (self.process.stdin, self.process.stdout):
            if pipe is not None and not pipe.closed:
                pipe.close()
        if not self.errors.closed and self.process.poll() is not None:
            self.errors.close()


def compile_in_background(module: str, *args: str) -> BackgroundCompile | None:
    """Start ``module.main(args)`` in a second Python process that shares this process's
    numba cache folder and imports the same msens; None if it cannot be started.

    Parameters
    ----------
    module : str
        An importable module with a ``main(argv) -> int`` function, e.g.
        ``"msens.chain.warmup"``; it may write a line to its standard output when a stage
        is done (:meth:`BackgroundCompile.wait_for`).
    *args : str
        Its arguments.
    """
    use_user_cache()  # the child inherits the environment: the same cache folder
    here = os.path.realpath(Path(__file__).resolve().parents[1])  # the folder holding msens
    errors = tempfile.TemporaryFile()
    try:
        process = subprocess.Popen([sys.executable, "-c", _CHILD, here, module, *args],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                   stderr=errors)
    except OSError:
        errors.close()
        return None
    return BackgroundCompile(process, errors)


def run_child(argv: list[str]) -> int:
    """The second process of :func:`compile_in_background`: ``argv[0]``'s ``main(argv[1:])``,
    ended early when the standard input closes."""

    def watch() -> None:
        # unbuffered reads (a thread blocked in a buffered read would abort the interpreter's
        # shutdown); an empty read: the parent closed the pipe or ended
        while os.read(stdin, 1024):
            pass
        os._exit(3)

    stdin = sys.stdin.fileno()

    threading.Thread(target=watch, name="msens-parent-watch", daemon=True).start()
    return importlib.import_module(argv[0]).main(argv[1:])
