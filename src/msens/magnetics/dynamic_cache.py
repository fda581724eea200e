"""Stored eddy-current models: :func:`dynamic_report` finds, reads or computes the frequency
responses of a geometry (artifact ``dynamic-<key>.json``, :mod:`msens.magnetics.dynamic` for
the physics), and serves a geometry whose coils alone changed from the model already solved
(:mod:`msens.magnetics.eddy_coil_read`) — as :mod:`msens.magnetics.transducer_cache` stores the
static transducers.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from msens.field.geometry import SensorGeometry
from msens.field.solve import FieldSolution
from msens.magnetics import eddy_coil_read
from msens.magnetics.dynamic import (
    DEFAULT_FREQUENCIES,
    RESPONSE_OFFSET_STEP,
    DynamicReport,
    eddy_sources,
    frequency_responses,
    join_reports,
    report_from_json,
    report_name,
    report_to_json,
)
from msens.magnetics.mechanisms import offset_grid
from msens.params.materials import SIGMA_1018
from msens.store import Store

_log = logging.getLogger(__name__)


def dynamic_report(geometry: SensorGeometry, *, options=None, store: Store | None = None,
                   frequencies: Sequence[float] = DEFAULT_FREQUENCIES,
                   steel: float = SIGMA_1018, magnets: Mapping[str, float] | None = None,
                   refresh: bool = False, workers: int | Callable = 1,
                   offsets: bool = False, start: FieldSolution | None = None
                   ) -> DynamicReport:
    """Stored :func:`frequency_responses` of a geometry (artifact ``dynamic-<key>.json``).

    The sources are those of the default static transducer (:func:`transducer_report`'s
    defaults: stress at the geometry's contact load, the steel's JAS law, both mechanisms);
    ``store`` (default :meth:`msens.store.Store.default`) finds, verifies and writes the
    responses and the meshes as for :func:`msens.magnetics.transducer_cache.transducer_report`.

    ``workers``: where the frequency solves run, in scipy's convention. 1 (default): here, in
    one task. An int n > 1: n local processes. A map-like callable ``workers(fn, iterable)``
    (e.g. :class:`msens.parallel.TaskMap` on a Dask cluster, made by the workflow): its
    tasks. With more than one worker the frequencies are split into one chunk per worker
    (``len(workers)`` of a map-like that has a length, else one chunk per frequency); each
    task meshes (through ``store``, which travels with it), solves the bias and the sources
    and then its frequencies, and the chunks are joined (:func:`join_reports`). The result
    equals the one-task result to round-off.

    With ``offsets`` each response also holds its coil's profiles over ±3 mm of axial offset
    (:data:`RESPONSE_OFFSET_STEP`; every source is then solved at every frequency), for
    :meth:`FrequencyResponse.shifted`; a separate artifact.

    ``start``: the geometry's bias solution on the plain mesh (``options=None``, e.g.
    :attr:`msens.magnetics.transducer.TransducerReport.bias`), where the eddy mesh's Newton
    starts; without it that solution is solved first (the same start, so the same result).

    A geometry whose eddy-current model is not stored but whose sensors were solved with
    other coils (the same everything else) reads its changed coils from that model
    (:mod:`msens.magnetics.eddy_coil_read`) instead of solving a new one.
    """

    store = Store.default() if store is None else store
    grid = offset_grid(RESPONSE_OFFSET_STEP).tolist() if offsets else None
    tkey, name = report_name(geometry, options, frequencies, steel, magnets, grid)
    free = eddy_coil_read.free_key(geometry, options, frequencies, steel, magnets, grid)
    data = None if refresh else store.read_json(name)
    if data is not None:
        rep = report_from_json(data)
        eddy_coil_read.record_model(store, free, geometry, rep)
        return rep
    if not refresh:  # the same sensors with other coils solved before: read this one
        rep = eddy_coil_read.read_changed_coils(
            geometry, free, store=store, options=options, frequencies=frequencies,
            steel=steel, magnets=magnets, offsets=grid)
        if rep is not None:
            return rep
    freqs = [float(f) for f in frequencies]
    from msens.progress import heartbeat

    _log.info("eddy-current responses (cached: no): %d frequencies", len(freqs))
    with heartbeat(_log, "eddy-current responses"):  # minutes of complex solves
        if workers == 1:
            rep = _report_task((geometry, options, store, freqs, steel, magnets, grid, start,
                                True))
        else:
            mapper, n = _task_map(workers, len(freqs) - 1)
            chunks = [c for c in np.array_split(np.asarray(freqs[1:]), n) if c.size]
            tasks = [(geometry, options, store, [0.0, *c.tolist()], steel, magnets, grid,
                      None, i == 0) for i, c in enumerate(chunks)]  # one chunk splits
            rep = join_reports(list(mapper(_report_task, tasks)))
    rep.details["transducer_key"] = tkey
    if store.write_json(name, report_to_json(rep), optional=True) is not None:
        eddy_coil_read.record_model(store, free, geometry, rep)
    return rep


def _task_map(workers: int | Callable, tasks: int) -> tuple[Callable, int]:
    """The map and the chunk count of ``workers`` (:func:`dynamic_report`) for ``tasks``
    independent frequencies."""
    if callable(workers):
        return workers, len(workers) if hasattr(workers, "__len__") else max(1, tasks)
    from msens.parallel import TaskMap, check_workers

    n = check_workers(workers)
    return TaskMap(workers=n), n


def _report_task(args: tuple) -> DynamicReport:
    """Mesh, bias, sources and the harmonic solves of one list of frequencies (from 0)."""
    from msens.progress import timed

    geometry, options, store, freqs, steel, magnets, offsets, start, screening = args
    with timed(_log, "eddy currents: mesh, bias solve and sources"):
        model = eddy_sources(geometry, options, store=store, start=start)
    sol = model.solution
    rep = frequency_responses(model, geometry, freqs, steel=steel, magnets=magnets,
                              offsets=offsets, screening=screening)
    rep.details["bias_newton_iterations"] = sol.iterations
    return rep


__all__ = ["dynamic_report"]
