"""``msens uq``: a study's prediction as bands, and which input to measure.

Order of work: every check of the user's input first (output folder, figure format, sample
count, workers or scheduler, the uncertainty file against the study) so that bad input ends
in one :class:`~msens.errors.InputError` before any solve; then the study's Eq. 10
calibration if it asks for one (its fitted dissipation becomes the nominal value); the
nominal prediction (the ``msens run`` numbers); the propagation
(:func:`msens.uq.propagate.propagate`); and the files: ``uq.json`` (strict JSON, written
atomically), ``uq_waveforms.<format>`` and ``uq_sobol.<format>``.

Where the work runs is decided here: a Dask scheduler when ``scheduler`` is given, else
local worker processes when the caller allows pools (the ``msens`` command does,
:func:`msens.parallel.pools_allowed`), else this process.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from msens.config.study import Study
from msens.io.output import DPI, OutputDir
from msens.parallel import check_scheduler, check_workers, one_blas_thread, pools_allowed
from msens.results import JsonReport
from msens.uq.inputs import InputSet, load_inputs
from msens.uq.propagate import Propagation, check_samples, propagate

_log = logging.getLogger(__name__)

FILES = ("uq.json", "uq_waveforms.png", "uq_sobol.png")
#: Default N of the Saltelli scheme (N (p + 2) model runs: 4,096 for the main study's 14
#: propagated inputs): the smallest power of two at which the main study's Sobol indices
#: agree with those of 4N within 0.05 (``benchmarks/uq_convergence.py``).
DEFAULT_SAMPLES = 256


@dataclass(frozen=True)
class UqResult(JsonReport):
    """What :func:`run_uq` produced.

    Attributes
    ----------
    propagation : Propagation
    report : dict
        The content of ``uq.json``.
    written : tuple of Path
    """

    propagation: Propagation
    report: dict
    written: tuple[Path, ...]

    def table(self) -> str:
        """What ``msens uq`` prints: the table
        (:func:`msens.uq.report.format_table`) and the files written."""
        from msens.tables import files_line
        from msens.uq.report import format_table

        return f"{format_table(self.report)}\n\n{files_line(self.written)}"


def _calibrated(study: Study) -> Study:
    # a study that asks for the Eq. 10 fit: its fitted dissipation as the nominal values
    if study.dissipation_fit is None:
        return study
    from msens.pipeline import calibrate_dissipation, output_times

    fit = calibrate_dissipation(study, output_times(study))
    return study.replace({"chain.gamma_contact_kg_per_s": fit.gamma_c,
                          "chain.gamma_wall_kg_per_s": fit.gamma_w, "calibration": None})


def nominal_features(study: Study, inputs: InputSet) -> dict[str, float]:
    """Every output at the inputs' nominal values: the ``msens run`` prediction."""
    from msens.uq.model import Task, evaluate

    row = np.array([[p.nominal for p in inputs.propagated]])
    ev = evaluate(Task(study, inputs, row, np.array([False])))
    return {k: float(v[0]) for k, v in ev.features.items()}


@one_blas_thread()
def run_uq(study: Study, out: str | Path, *, inputs: str | Path | None = None,
           samples: int = DEFAULT_SAMPLES, seed: int = 0, scheduler: str | None = None,
           workers: int | None = None, fig_format: str = "png",
           progress: bool = True) -> UqResult:
    """Propagate a study's uncertain inputs; write ``uq.json`` and the two figures.

    Parameters
    ----------
    study : Study
    out : str or Path
        Output directory.
    inputs : str or Path, optional
        Uncertainty file (``msens.uncertainty/1``); default the built-in one of a built-in
        study.
    samples : int
        N of the Saltelli scheme, a power of two.
    seed : int
        Seed of the samples and of the indices' bootstrap (same seed, same numbers).
    scheduler : str, optional
        Dask scheduler address (``tcp://host:port``).
    workers : int, optional
        Local worker processes (default: all CPUs when pools are allowed, else 1).
    fig_format : {"png", "pdf", "svg"}
    progress : bool
        A progress bar on stderr.

    Returns
    -------
    UqResult

    Raises
    ------
    InputError
        Before any solve, for any bad input (see the module docstring).
    """
    from msens import plots
    from msens.errors import InputError
    from msens.uq import report as rep
    from msens.workflows.common import check_format, figure_names, provenance

    names = figure_names(FILES, check_format(fig_format))
    target = OutputDir(out)
    target.check(names)
    check_samples(samples)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
        raise InputError(f"--seed must be a whole number from 0 to 2**32 - 1, got {seed!r}")
    scheduler = check_scheduler(scheduler)
    workers = check_workers(workers)
    load_inputs(inputs, study)  # every input checked before any work
    from msens import budget
    from msens.progress import heartbeat, refreshing

    budget.check(study)
    _log.info("uq: the nominal prediction (msens run) and the models the inputs need")
    with heartbeat(_log, "uq: the nominal prediction"):
        study = _calibrated(study)
        checked = load_inputs(inputs, study)
        nominal = nominal_features(study, checked)
    if scheduler is None and workers is None and not pools_allowed():
        workers = 1
    bar = None
    if progress and _log.isEnabledFor(logging.INFO):
        from tqdm import tqdm

        bar = tqdm(desc="uq model runs", unit=" runs", leave=False)

    def tick(done: int, total: int) -> None:
        if bar is not None:
            bar.total = total
            bar.n = done
            bar.refresh()

    try:
        with refreshing(bar):
            result = propagate(study, checked, samples=samples, seed=seed,
                               scheduler=scheduler, workers=workers, progress=tick)
    finally:
        if bar is not None:
            bar.close()
    _log.info("uq: writing uq.json and the figures to %s", target.path)
    with heartbeat(_log, "uq: writing uq.json and the figures"):
        report = rep.to_json(result, nominal, provenance=provenance(study), study=study)
        written = [target.write_json("uq.json", report)]
        for name, make in ((names[1], lambda: rep.waveform_figure(result)),
                           (names[2], lambda: rep.sobol_figure(result))):
            fig = make()
            written.append(target.savefig(name, fig, fmt=fig_format, dpi=DPI))
            plots.close(fig)
    return UqResult(propagation=result, report=report, written=tuple(written))


__all__ = ["DEFAULT_SAMPLES", "FILES", "UqResult", "nominal_features", "run_uq"]
