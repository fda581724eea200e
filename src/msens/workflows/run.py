"""The run workflow: simulate every setup of a study, then write and print its results.

:func:`run` checks the request (the study's budget, the scheduler's address) and runs the
study (:func:`msens.pipeline.run_study`); :func:`write_outputs` writes ``summary.json`` and
the figures into a folder checked beforehand (:func:`prepare_outputs`), never over a user's
file. The run's result is a :class:`~msens.results.StudyResult`: its ``to_json()`` is the
content of ``summary.json`` and its ``table()`` the terminal's table
(:func:`format_summary`).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from msens import results
from msens.config.study import Study
from msens.io.output import DPI, OutputDir
from msens.pipeline import run_study
from msens.results import StudyResult
from msens.tables import format_summary as format_summary
from msens.workflows.common import check_format, figure_names, provenance

#: Figures of every run (listed as PNG; written in the chosen format).
FIGURES = ("contact_forces.png", "sensor_profiles.png", "sensor_records.png", "table2.png")
#: Figures of a run with physics MsS sensors.
PHYSICS_FIGURES = ("mss_voltage.png", "mss_integrated.png", "sensitivity_profile.png",
                   "magnetic_precompression.png", "field_B.png")


def run(study: Study, *, scheduler: str | None = None) -> StudyResult:
    """Calibrate, simulate and observe every setup of ``study`` (the eddy-current frequency
    solves on the Dask cluster at ``scheduler`` when given, else in this process).

    Where the work runs is decided here: the physics takes a map-like ``workers``
    (:class:`msens.parallel.TaskMap` over the cluster) and never sees the address."""
    from msens import preflight
    from msens.parallel import TaskMap

    # the address is checked even when no remote work turns out to be needed
    preflight.study(study)
    scheduler = preflight.check_scheduler(scheduler)
    return run_study(study, workers=1 if scheduler is None else TaskMap(scheduler=scheduler))


def summary(result: StudyResult) -> dict:
    """The content of ``summary.json`` (:func:`msens.results.summary` with this run's
    provenance)."""
    return results.summary(result, provenance(result.study))


def prepare_outputs(out: str | Path, *, figures: bool = True,
                    fig_format: str = "png") -> OutputDir:
    """Open ``out`` and check, before any work, that no user file would be overwritten.

    ``fig_format`` ("png", "pdf" or "svg") names the figures to check.
    """
    check_format(fig_format)
    d = OutputDir(out)
    d.check(["summary.json",
             *(figure_names(FIGURES + PHYSICS_FIGURES, fig_format) if figures else ())])
    return d


def figure_makers(result: StudyResult) -> dict:
    """The figures this result has, as {file name (PNG): function making the figure}."""
    from msens import plots, plots_mss

    makers = {
        "contact_forces.png": lambda: plots.contact_profiles(result),
        "sensor_records.png": lambda: plots.sensor_records(result),
    }
    if any(s.setup.inserts or len(result.setups) > 1 for s in result.setups):
        makers["sensor_profiles.png"] = lambda: plots.sensor_profiles(result)
    if result.study.reference:
        makers["table2.png"] = lambda: plots.table2(result.rows(), result.study.name)
    if any(s.transducers for s in result.setups):
        makers["mss_voltage.png"] = lambda: plots_mss.mss_voltages(result)
        makers["mss_integrated.png"] = lambda: plots_mss.mss_integrated(result)
        makers["sensitivity_profile.png"] = lambda: plots_mss.sensitivity_profile(result)
        makers["magnetic_precompression.png"] = lambda: plots_mss.magnetic_precompression(result)
    return makers


def _field_map(result: StudyResult, d: OutputDir, fig_format: str = "png") -> Path | None:
    """The bias-field map of the first physics setup (re-solves the cached field model)."""
    from msens.config.fieldsetup import geometry_from_study
    from msens.field.sensor_model import run_field_model
    from msens.field_outputs import plot_field_map

    setup = next((s.setup for s in result.setups if s.transducers), None)
    if setup is None:
        return None
    from msens.magnetics.transducer_cache import solved_for

    geometry = geometry_from_study(result.study, setup)
    # a coil read from another coil's field model: the same bias field, on that model's mesh
    report = replace(run_field_model(solved_for(geometry), inductance=False), geometry=geometry)
    return d.write(f"field_B.{fig_format}", lambda p: plot_field_map(report, p, fig_format))


def write_outputs(result: StudyResult, out: str | Path | OutputDir, *,
                  figures: bool = True, fig_format: str = "png") -> list[Path]:
    """Write ``summary.json`` and the figures (in ``fig_format``: "png", "pdf" or "svg")
    into ``out``; returns the written paths."""
    from msens import plots

    check_format(fig_format)
    d = out if isinstance(out, OutputDir) else prepare_outputs(out, figures=figures,
                                                               fig_format=fig_format)
    written = [d.write_json("summary.json", summary(result))]
    if figures:
        for name, make in figure_makers(result).items():
            fig = make()
            written.append(d.savefig(name, fig, fmt=fig_format, dpi=DPI))
            plots.close(fig)
        field_map = _field_map(result, d, fig_format)
        if field_map is not None:
            written.append(field_map)
    return written
