"""Run design tasks through the executor with a resumable cache and a progress bar.

Each task is ``(key, payload)``; results found in the cache are taken from it, the others are
computed through :func:`msens.parallel.run_tasks` and stored the moment they arrive. A task
function never raises for a bad design: :func:`guarded` turns an exception into a ``failed``
record with its reason, so the sweep goes on.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Sequence
from typing import Any

from tqdm import tqdm

from msens.design.cache import ResultCache
from msens.parallel import run_tasks


def guarded(fn: Callable[[Any], dict], payload: Any) -> dict:
    """``{"status": "ok", **fn(payload)}``, or ``{"status": "failed", "reason": ...}``."""
    try:
        return {"status": "ok", **fn(payload)}
    except Exception as exc:  # a failed design is a result, not a crash
        last = traceback.extract_tb(exc.__traceback__)[-1]
        where = f" (at {last.name}:{last.lineno})" if last else ""
        reason = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        return {"status": "failed", "reason": reason + where}


class _Guarded:
    """Picklable ``payload -> guarded(fn, payload)``."""

    def __init__(self, fn: Callable[[Any], dict]):
        self.fn = fn

    def __call__(self, payload: Any) -> dict:
        return guarded(self.fn, payload)


def run_cached(fn: Callable[[Any], dict], tasks: Sequence[tuple[str, Any]],
               cache: ResultCache, *, scheduler: str | None = None,
               workers: int | None = None, progress: bool = True,
               description: str = "designs", unit: str = "design"
               ) -> tuple[list[dict], int]:
    """Results of all tasks, in task order, and how many were computed (not cached).

    Parameters
    ----------
    fn : callable
        Module-level ``payload -> dict`` of one design.
    tasks : sequence of (str, object)
        Cache key and payload per task.
    cache : ResultCache
    scheduler, workers
        See :func:`msens.parallel.run_tasks`.
    progress : bool
        Show a tqdm bar on stderr.
    description, unit : str
        The bar's label and the name of one task.
    """
    results: list[dict | None] = [cache.get(key) for key, _ in tasks]
    todo = [i for i, r in enumerate(results) if r is None]
    bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc=description,
               unit=unit, disable=not progress)
    try:
        for j, result in run_tasks(_Guarded(fn), [tasks[i][1] for i in todo],
                                   scheduler=scheduler, workers=workers):
            i = todo[j]
            cache.put(tasks[i][0], result)
            results[i] = cache.get(tasks[i][0])  # exactly what a resumed run reads
            bar.update(1)
    finally:
        bar.close()
    return [r for r in results if r is not None], len(todo)


__all__ = ["guarded", "run_cached"]
