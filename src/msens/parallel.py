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

import multiprocessing
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

from msens.errors import InputError

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
        Local worker processes (default :func:`default_workers`); ignored with Dask.

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
    n = default_workers() if workers is None else workers
    if n < 1:
        raise InputError(f"workers must be >= 1, got {n}")
    if n == 1 or len(args) == 1:
        for i, a in enumerate(args):
            yield i, fn(a)
        return
    ctx = multiprocessing.get_context("forkserver")
    k = min(n, len(args))
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


def _share_cores(threads: int) -> None:
    """Worker start: BLAS and OpenMP get the worker's share of the cores. Each library
    otherwise starts a thread per core in every worker: two workers on two cores ran a
    contact map's solves 1.5x slower each than one worker alone; with one thread each, as
    fast."""
    from threadpoolctl import threadpool_limits

    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(threads)  # libraries the tasks load later
    threadpool_limits(limits=threads)  # and those already loaded


def _run_dask(fn: Callable[[Any], Any], args: Sequence[Any],
              scheduler: str) -> Iterator[tuple[int, Any]]:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # an optional extra: the base install has no dask
        raise InputError('--scheduler needs dask.distributed, which is not installed: '
                         'pip install "msens[cluster]"') from exc
    try:
        client = Client(scheduler, timeout="10s")
    except OSError as exc:
        raise InputError(f"cannot connect to the Dask scheduler at {scheduler!r}: {exc}") \
            from exc
    try:
        futures = [client.submit(fn, a, pure=False) for a in args]
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            yield index[fut.key], fut.result()
    finally:
        client.close()


__all__ = ["allow_pools", "default_workers", "pools_allowed", "run_tasks"]
