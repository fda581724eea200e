"""One executor interface for independent tasks: local processes or a Dask cluster.

:func:`run_tasks` maps a picklable, module-level function over a sequence of picklable
arguments and yields ``(index, result)`` pairs as tasks finish (any order). The caller
decides what to do with each result as it arrives (cache it, update a progress bar), so an
interrupted run loses at most the tasks in flight.

- ``scheduler=None`` (default): a :class:`concurrent.futures.ProcessPoolExecutor` with the
  ``forkserver`` start method (no fork of a process that already runs threads), its
  workers' BLAS limited to their share of the cores; or the calling process itself when
  ``workers == 1`` (no pickling, easiest to debug).
- ``scheduler="tcp://host:port"``: a running ``dask.distributed`` scheduler; tasks are
  submitted with ``pure=False`` so Dask never merges or reorders them by its own hashing.
  Dask is optional (``pip install "msens[cluster]"``); without it this is an InputError.

Results do not depend on where a task ran: each task is a pure function of its argument.
"""

from __future__ import annotations

import functools
import logging
import multiprocessing
import os
import re
import socket
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, ThreadPoolExecutor, wait
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

from msens.errors import InputError, shorten

#: Seconds to wait for a Dask scheduler to accept a connection when its address is checked.
CONNECT_TIMEOUT_S = 5.0
#: ``[tcp://]host:port``: a host name, an IPv4 address or a bracketed IPv6 address.
_ADDRESS_RE = re.compile(r"(?:(?P<proto>[A-Za-z][A-Za-z0-9+.-]*)://)?"
                         r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)"
                         r"(?::(?P<port>[0-9]{1,5}))?/?")
_ADDRESS_HELP = ("a Dask scheduler address is tcp://host:port (e.g. tcp://10.0.0.5:8786, as "
                 "'dask scheduler' prints it); leave --scheduler out to run on this machine")


def check_scheduler(address: object, *, connect: bool = True) -> str | None:
    """The Dask scheduler ``address`` checked before any work: its form, then that
    dask.distributed is installed, then (``connect``) that something accepts a connection
    there within :data:`CONNECT_TIMEOUT_S`.

    Parameters
    ----------
    address : str or None
        ``tcp://host:port`` or ``host:port``; None means local work (returned as is).
    connect : bool
        Also open (and close) a TCP connection to the address.

    Returns
    -------
    str or None
        The address with ``tcp://`` (None for None).

    Raises
    ------
    InputError
        Naming the address and what is wrong: malformed (empty, no port, another protocol:
        ``inproc://`` exists only inside one process, ``tls://`` needs security settings msens
        does not pass), dask missing, or nothing listening.
    """
    if address is None:
        return None
    if not isinstance(address, str):
        raise InputError(f"--scheduler must be an address string, got "
                         f"{type(address).__name__} {shorten(address)}; {_ADDRESS_HELP}")
    text = address.strip()
    if not text:
        raise InputError(f"--scheduler is empty; {_ADDRESS_HELP}")
    m = _ADDRESS_RE.fullmatch(text)
    if m is None:
        raise InputError(f"--scheduler {shorten(address)} is not an address; {_ADDRESS_HELP}")
    proto, host, port = m.group("proto"), m.group("host"), m.group("port")
    if proto is not None and proto.lower() != "tcp":
        why = {"inproc": "an in-process address exists only inside the process that made it",
               "tls": "TLS needs certificates msens does not pass",
               "ucx": "UCX is not supported"}.get(proto.lower(), "an unknown protocol")
        raise InputError(f"--scheduler {shorten(address)}: protocol {proto}:// is not "
                         f"supported ({why}); {_ADDRESS_HELP}")
    if port is None:
        raise InputError(f"--scheduler {shorten(address)} has no port; {_ADDRESS_HELP}")
    if not 1 <= int(port) <= 65535:
        raise InputError(f"--scheduler {shorten(address)}: port {int(port)} is not from 1 to "
                         f"65535; {_ADDRESS_HELP}")
    _need_distributed()
    canonical = f"tcp://{host}:{int(port)}"
    if connect:
        try:
            with socket.create_connection((host.strip("[]"), int(port)),
                                          timeout=CONNECT_TIMEOUT_S):
                pass
        except (OSError, UnicodeError) as exc:
            reason = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
            raise InputError(f"--scheduler {shorten(address)}: no Dask scheduler answers "
                             f"there ({reason}); start one ('dask scheduler') or check the "
                             "address") from None
    return canonical


def check_workers(workers: object) -> int | None:
    """``workers`` (local worker processes) checked: None (all CPUs) or an integer >= 1.

    Raises
    ------
    InputError
        For 0, negative counts, fractions, booleans and non-numbers.
    """
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int):
        raise InputError(f"--workers must be a whole number of processes >= 1, got "
                         f"{shorten(workers)}")
    if workers < 1:
        raise InputError(f"--workers must be >= 1 (leave it out to use all "
                         f"{default_workers()} CPUs), got {workers}")
    return workers


def _need_distributed() -> None:
    """InputError if dask.distributed (an optional extra) is not installed."""
    try:
        import distributed  # noqa: F401
    except ImportError as exc:
        raise InputError('--scheduler needs dask.distributed, which is not installed: '
                         'pip install "msens[cluster]"') from exc

#: Whether a library call may start its own local process pool (see :func:`pools_allowed`).
_POOLS_ALLOWED: ContextVar[bool] = ContextVar("msens_pools_allowed", default=False)


@contextmanager
def allow_pools(allowed: bool = True) -> Iterator[None]:
    """Let library calls inside the block start local process pools (the ``msens`` console
    command does; restored after)."""
    token = _POOLS_ALLOWED.set(bool(allowed))
    try:
        yield
    finally:
        _POOLS_ALLOWED.reset(token)


def pools_allowed() -> bool:
    """True inside :func:`allow_pools` and outside any worker process.

    A library function that would parallelise on its own (the cold contact maps) asks this
    first: a pool's workers import the caller's main script, so a user's script without an
    ``if __name__ == "__main__":`` guard would run again in every worker and fail.
    """
    return _POOLS_ALLOWED.get() and multiprocessing.parent_process() is None


def default_workers() -> int:
    """Worker processes used by default: the CPUs available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_tasks(fn: Callable[[Any], Any], args: Sequence[Any], *,
              scheduler: str | None = None,
              workers: int | None = None) -> Iterator[tuple[int, Any]]:
    """Run ``fn(a)`` for every ``a`` in ``args``; yield ``(index, result)`` as tasks finish.

    Parameters
    ----------
    fn : callable
        A module-level function (picklable by reference).
    args : sequence
        Picklable arguments, one task each.
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:port``); None = local.
    workers : int, optional
        Local worker processes (default :func:`default_workers`; never more than that, nor
        more than the tasks); ignored with Dask.

    Yields
    ------
    (int, object)
        Index into ``args`` and the task's return value. An exception raised by ``fn``
        propagates (functions that must not stop a sweep catch their own errors).
    """
    if not args:
        return
    if scheduler is not None:
        yield from _run_dask(fn, args, scheduler)
        return
    n = default_workers() if workers is None else check_workers(workers)
    if n == 1 or len(args) == 1:
        for i, a in enumerate(args):
            yield i, fn(a)
        return
    ctx = multiprocessing.get_context("forkserver")
    # more processes than CPUs only multiply the memory (each may hold a field model):
    # --workers 1000 on a magnet sweep of 24 designs would start 24 solvers on 2 cores
    k = min(n, len(args), default_workers())
    if k < min(n, len(args)):
        logging.getLogger(__name__).info(
            "%d worker processes asked for, %d CPUs available: using %d", n,
            default_workers(), k)
    with ProcessPoolExecutor(max_workers=k, mp_context=ctx, initializer=_share_cores,
                             initargs=(max(1, default_workers() // k),)) as pool:
        pending = {pool.submit(fn, a): i for i, a in enumerate(args)}
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in sorted(done, key=pending.__getitem__):
                    i = pending.pop(fut)
                    yield i, fut.result()
        finally:
            for fut in pending:
                fut.cancel()


@functools.cache
def _blas():
    """The process's BLAS libraries, found once (a search reads /proc, ~3 ms per call)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """A context (and decorator) in which BLAS runs on one thread.

    For work made of many small dense products and solves (a sparse LU's blocks, the
    design's batched spectra, a diagnosis's or calibration's profiled likelihoods): they
    gain nothing from threads, and OpenBLAS's threads on a loaded machine wait for a time
    slice on every call. Measured on 2 cores with one other busy process: a diagnosis of
    the main study's two-shot file 317 s with OpenBLAS's threads, 109 s with one (its
    alignments 196 s -> 12 s); a sparse factor jumped between 0.03 s and 5.8 s (cf. scipy
    issue 13999); a design's spectrum chunk 0.2 s instead of 0.02 s at load 5.
    """
    with _blas().limit(limits=1, user_api="blas"):
        yield


def thread_map(fn: Callable[[Any], Any], items: Sequence[Any], threads: int = 1) -> list:
    """``[fn(x) for x in items]``, on ``threads`` threads of this process, BLAS on one thread
    each (:func:`one_blas_thread`).

    For work whose time is spent in numpy, BLAS and pocketfft calls that release the GIL
    (a coil sweep's chunks of spectra and inverse FFTs): threads share the process's
    arrays, where worker processes would each need a copy of a coil sweep's ~150 MB
    context. ``threads`` is decided by the caller (a workflow: :func:`default_workers`
    for a local run); 1 runs in the calling thread.
    """
    with one_blas_thread():
        if threads <= 1 or len(items) <= 1:
            return [fn(x) for x in items]
        with ThreadPoolExecutor(max_workers=min(threads, len(items))) as pool:
            return list(pool.map(fn, items))


def _share_cores(threads: int) -> None:
    """Worker start: BLAS and OpenMP get the worker's share of the cores. Each library
    otherwise starts a thread per core in every worker: two workers on two cores ran a
    contact map's solves 1.5x slower each than one worker alone; with one thread each, as
    fast."""
    from threadpoolctl import threadpool_limits

    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(threads)  # libraries the tasks load later
    threadpool_limits(limits=threads)  # and those already loaded


@dataclass(frozen=True)
class TaskMap:
    """A map-like callable over :func:`run_tasks`, made where a workflow decides where its
    work runs and handed to physics functions as their ``workers`` (scipy's ``workers=``
    convention: an int or a map-like ``workers(fn, iterable)``).

    Parameters
    ----------
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:port``); None = local.
    workers : int, optional
        Local worker processes (default :func:`default_workers`); ignored with Dask.
    """

    scheduler: str | None = None
    workers: int | None = None

    def __call__(self, fn: Callable[[Any], Any], iterable: Iterable[Any]) -> list[Any]:
        """``[fn(a) for a in iterable]``, run where this map says, in the order of
        ``iterable``."""
        args = list(iterable)
        out: list[Any] = [None] * len(args)
        for i, result in run_tasks(fn, args, scheduler=self.scheduler, workers=self.workers):
            out[i] = result
        return out

    def __bool__(self) -> bool:
        """Always true (truth must not ask a Dask cluster for its workers, as ``len`` does)."""
        return True

    def __len__(self) -> int:
        """Workers this map runs on: those of the Dask cluster (asked once per call, at
        least 1), else the local worker processes."""
        if self.scheduler is not None:
            return dask_workers(self.scheduler)
        return default_workers() if self.workers is None else check_workers(self.workers)


def dask_workers(scheduler: str) -> int:
    """Workers of the Dask scheduler at ``scheduler`` (at least 1)."""
    scheduler = check_scheduler(scheduler, connect=False)  # the form, then dask installed
    from distributed import Client

    with Client(scheduler) as client:
        return max(1, len(client.scheduler_info()["workers"]))


def _run_dask(fn: Callable[[Any], Any], args: Sequence[Any],
              scheduler: str) -> Iterator[tuple[int, Any]]:
    scheduler = check_scheduler(scheduler, connect=False)  # the form, then dask installed
    from distributed import Client, as_completed

    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, ValueError, TypeError) as exc:  # distributed's parse errors are ValueError
        raise InputError(f"cannot connect to the Dask scheduler at {shorten(scheduler)}: "
                         f"{shorten(str(exc), 200)}") from None
    try:
        futures = [client.submit(fn, a, pure=False) for a in args]
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            yield index[fut.key], fut.result()
    finally:
        client.close()


__all__ = ["TaskMap", "allow_pools", "check_scheduler", "check_workers", "dask_workers",
           "default_workers", "pools_allowed", "run_tasks"]
