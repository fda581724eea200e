"""The design workflow: sweep coil or magnet designs of a study's MsS sensor.

The request is checked first (the study, the scheduler's address, the worker count, the
output folder, the study's run budget); the sweep itself, its cache and its files
(``designs.csv``, the Pareto figure, ``recommendation.json``) are
:func:`msens.design.run_design`'s, and so is the result, a :class:`msens.design.DesignResult`
(its text table: :func:`msens.tables.format_design`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from msens import budget, preflight
from msens.config.study import Study
from msens.tables import format_design as format_design
from msens.workflows.common import check_format, provenance

if TYPE_CHECKING:
    from msens.design.workflow import DesignResult


def design(study: Study, sweep: str | Path, out: str | Path, *, scheduler: str | None = None,
           workers: int | None = None, progress: bool = True,
           fig_format: str = "png") -> DesignResult:
    """Sweep coil/magnet designs of the study's MsS (:mod:`msens.design`); writes
    ``designs.csv``, ``pareto.<fig_format>`` and ``recommendation.json`` into ``out``.

    Parameters
    ----------
    study : Study
        A study with at least one MsS sensor (its coil and magnet are the base design).
    sweep : str or Path
        The sweep file (TOML).
    out : str or Path
        Output folder; its ``cache/`` lets an interrupted sweep resume.
    scheduler : str, optional
        Dask scheduler address.
    workers : int, optional
        Local worker processes.
    progress : bool
        Show a progress bar.
    fig_format : {"png", "pdf", "svg"}
        Format of the Pareto figure.

    Returns
    -------
    DesignResult
        The recommendation (:meth:`~msens.design.DesignResult.to_json`: the content of
        ``recommendation.json``), the counts, the text table
        (:meth:`~msens.design.DesignResult.table`) and the files written.
    """
    # the sweep library loads when a sweep runs, not with msens.api
    from msens.design.sweep import load_sweep
    from msens.design.workflow import run_design

    preflight.study(study)
    scheduler = preflight.check_scheduler(scheduler)
    workers = preflight.check_workers(workers)
    out = preflight.output_dir(out)
    budget.check(study)
    return run_design(study, load_sweep(sweep), out, scheduler=scheduler, workers=workers,
                      progress=progress, provenance=provenance(study),
                      fig_format=check_format(fig_format))
