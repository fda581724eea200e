"""Feedback on long stages: a heartbeat while a stage runs, and the honest time estimates.

A stage that may run longer than a few seconds without a message of its own (the chain
kernel's first compilation, a nonlinear field solve, a diagnosis candidate's fit) runs
inside :func:`heartbeat`: a background thread logs ``<stage>: still working, 15 s`` every
:data:`HEARTBEAT_S` seconds until it ends, so the ``msens`` command is never silent for
long. The messages go to the ``msens`` loggers at INFO (the command shows them on stderr;
``-q`` hides them; a library user sees nothing unless they configure logging).

This module imports only the standard library: the command line reads its constants
before it loads numpy or numba.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

#: Seconds between two heartbeat lines (below 5 s: a thread woken late on a busy machine
#: still keeps the silence near 5 s).
HEARTBEAT_S = 4.0

#: Wall time of the chain kernel's first compilation on an idle 2-core machine, s: the
#: variant ``msens run`` needs is a single-threaded numba compile of about 25 s of CPU, done in
#: a second process (:mod:`msens.chain.warmup`); a loaded machine takes longer. It happens
#: once per install (the compiled code is kept in the user cache folder,
#: :mod:`msens.numba_cache`); measurements on docs/benchmarks.md.
KERNEL_COMPILE_S = 30.0


def duration_text(seconds: float) -> str:
    """``seconds`` as a person says it: ``"about 40 s"``, ``"about 1.5 min"``."""
    if seconds < 90:
        return f"about {seconds:.0f} s"
    return f"about {seconds / 60:.1f} min".replace(".0 min", " min")


#: :data:`KERNEL_COMPILE_S` in words, for messages and help texts.
COMPILE_ESTIMATE_TEXT = duration_text(KERNEL_COMPILE_S)


@contextmanager
def heartbeat(logger: logging.Logger, stage: str, *, every: float = HEARTBEAT_S,
              note: str = "") -> Iterator[None]:
    """Log ``<stage>: still working, <t> s<note>`` every ``every`` seconds while the
    ``with`` block runs.

    Parameters
    ----------
    logger : logging.Logger
        Where the lines go (at INFO); nothing is started unless it is enabled for INFO.
    stage : str
        What is running, e.g. ``"setup paper-mss: simulating the chain"``.
    every : float
        Seconds between lines (> 0).
    note : str
        Appended to each line, e.g. ``" (compiling the chain kernel on first use)"``.

    Heartbeats nest: one background thread speaks for the innermost running stage, so an
    outer stage is quiet while an inner one runs and speaks again as soon as it ends.
    """
    if not logger.isEnabledFor(logging.INFO):
        yield
        return
    entry = _Stage(logger, stage, note, every, time.perf_counter())
    with _COND:
        _STACK.append(entry)
        _LAST[0] = entry.start  # a stage starts with a line of its own, usually
        global _THREAD
        if _THREAD is None:
            _THREAD = threading.Thread(target=_tick, name="msens-heartbeat", daemon=True)
            _THREAD.start()
        _COND.notify_all()
    try:
        yield
    finally:
        with _COND:
            _STACK.remove(entry)
            thread = _THREAD if not _STACK else None
            _COND.notify_all()
        if thread is not None:
            thread.join()


@contextmanager
def refreshing(bar, *, every: float = 2.0) -> Iterator[None]:
    """Redraw a progress bar (tqdm) every ``every`` seconds while the ``with`` block runs.

    A bar moves when a task finishes; with tasks of several seconds on a busy machine it
    stood still for 10 s. Redrawn, its elapsed time and estimate move: the screen shows the
    work going on. ``bar=None`` (no bar: ``-q``) does nothing.
    """
    if bar is None:
        yield
        return
    stop = threading.Event()

    def redraw() -> None:
        while not stop.wait(every):
            bar.refresh()  # tqdm takes its own lock

    thread = threading.Thread(target=redraw, name="msens-bar", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def stopwatch() -> Callable[[], float]:
    """A function giving the wall seconds since this call (for progress lines that say how
    long a stage has run)."""
    start = time.perf_counter()
    return lambda: time.perf_counter() - start


@contextmanager
def timed(logger: logging.Logger, stage: str, *,
          level: int = logging.DEBUG) -> Iterator[Callable[[], float]]:
    """Log ``<stage>: <t> s`` at ``level`` (default DEBUG) when the ``with`` block ends.

    The timing of a computation's stages goes to the log, never into its results: the
    physics stays a function of its inputs. Yields a :func:`stopwatch` of the block.
    """
    elapsed = stopwatch()
    try:
        yield elapsed
    finally:
        if logger.isEnabledFor(level):
            logger.log(level, "%s: %.2f s", stage, elapsed())


@dataclass(frozen=True)
class _Stage:
    logger: logging.Logger
    stage: str
    note: str
    every: float
    start: float


#: The running stages, innermost last; when a heartbeat line was last logged
#: (time.perf_counter()); the thread that logs them (None while no stage runs).
_STACK: list[_Stage] = []
_LAST = [0.0]
_THREAD: threading.Thread | None = None
_COND = threading.Condition()


def _tick() -> None:
    """The heartbeat thread: a line for the innermost stage whenever none came for its
    ``every`` seconds; ends when no stage runs."""
    global _THREAD
    while True:
        with _COND:
            if not _STACK:
                _THREAD = None
                return
            entry = _STACK[-1]
            wait = _LAST[0] + entry.every - time.perf_counter()
            if wait > 0:
                _COND.wait(wait)
                continue
            now = time.perf_counter()
            _LAST[0] = now
        entry.logger.info("%s: still working, %.0f s%s", entry.stage, now - entry.start,
                          entry.note)
