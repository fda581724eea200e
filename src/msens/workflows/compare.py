"""The compare workflow: a measured waveform against the model of a study.

The measurement is checked against the study file first (unit, channels, complete shots,
plausible amplitudes, a pulse in every record), so mismatched data fail in about a second,
then once more against the model's run (records neither inverted nor time-scaled). The same
checks open a diagnosis (:func:`check_measurement`). The comparison itself is
:func:`msens.compare.compare`; this module writes ``compare.json`` and the overlay figure
and returns them as a :class:`CompareResult` (its text table:
:func:`msens.tables.format_comparison`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from msens import budget
from msens.compare import (
    check_signal,
    check_units,
    match_setup,
    match_setup_spec,
    shot_records,
)
from msens.compare import compare as compare_records
from msens.config.study import Study
from msens.io.output import DPI, OutputDir, to_json
from msens.io.waveform import Waveform
from msens.parallel import one_blas_thread
from msens.pipeline import run_study
from msens.results import JsonReport, StudyResult
from msens.signals.signalcheck import check_amplitudes, check_pulses, check_shots
from msens.tables import files_line
from msens.tables import format_comparison as format_comparison
from msens.workflows.common import check_format, figure_names, provenance

#: The files ``compare`` writes (the overlay in the chosen figure format).
FILES = ("compare.json", "overlay.png")


@dataclass(frozen=True)
class CompareResult(JsonReport):
    """What ``compare`` produced: the comparison and the files written.

    Attributes
    ----------
    report : dict
        The content of ``compare.json`` as plain JSON values (per channel the measured
        features over the shots and the model's; TOF in µs; non-finite numbers are None);
        read it through :meth:`to_json`, which returns a copy.
    written : tuple of Path
        The files written: ``compare.json``, then the overlay figure (also :attr:`files`;
        :attr:`figures` the figure alone).
    """

    report: dict
    written: tuple[Path, ...]

    def table(self) -> str:
        """What ``msens compare`` prints: the table (:func:`format_comparison`) and the
        files written."""
        return f"{format_comparison(self.report)}\n\n{files_line(self.files)}"


def check_measurement(study: Study, waveform: Waveform, source: str) -> StudyResult:
    """Check a measured waveform against ``study`` and return the model's run.

    The checks on the study file come first (the data's unit, a setup with exactly the
    data's sensors, complete shots, plausible amplitudes, a pulse in every record); then the
    study is run (seconds) and the records are checked against the model's: neither
    inverted nor time-scaled.

    Parameters
    ----------
    study : Study
    waveform : Waveform
        The measurement (volts).
    source : str
        Where the waveform came from, for messages.

    Returns
    -------
    StudyResult
        The model's run of ``study``.

    Raises
    ------
    InputError
        Naming ``source`` and what does not match.
    """
    check_units(waveform)
    match_setup_spec(study, waveform)
    check_shots(waveform, source)
    check_amplitudes(waveform, source)
    check_pulses(waveform, source)  # no signal is an error, in compare as in diagnose
    budget.check_record_rate(study, waveform, source)  # the same bound as a study's rates
    result = run_study(study)
    check_signal(match_setup(result, waveform), waveform, source)
    return result


@one_blas_thread()
def compare(study: Study, data: Path, out: Path, *,
            fig_format: str = "png") -> CompareResult:
    """Compare measured ``data`` with the model of ``study``; write ``compare.json`` and an
    overlay figure (``overlay.<fig_format>``: png, pdf or svg) into ``out``.

    Parameters
    ----------
    study : Study
    data : Path
        A waveform file (CSV, NPZ or TDMS), or a column-mapped source
        (:mod:`msens.io.columns`).
    out : Path
        Output folder; files of the same names that msens did not write are never
        overwritten.
    fig_format : {"png", "pdf", "svg"}

    Returns
    -------
    CompareResult
        The content of ``compare.json`` (:meth:`CompareResult.to_json`), the text table
        (:meth:`CompareResult.table`) and the files written.

    Raises
    ------
    InputError
        If ``out`` holds user files of the same names, the data's metadata give a unit
        other than V, no setup of the study has exactly the data's sensors, or a record
        has no pulse to compare (:func:`check_measurement`).
    """
    from msens import plots
    from msens.io.read import read_waveform

    target = OutputDir(out)
    target.check(figure_names(FILES, check_format(fig_format)))
    waveform = read_waveform(data)
    result = check_measurement(study, waveform, str(getattr(data, "path", data)))
    report = compare_records(result, waveform)
    report["data"] = str(data)
    report["provenance"] = provenance(study)
    written = [target.write_json("compare.json", report)]
    setup = match_setup(result, waveform)
    fig = plots.overlay(setup, shot_records(setup, waveform))
    written.append(target.savefig("overlay.png", fig, fmt=fig_format, dpi=DPI))
    plots.close(fig)
    return CompareResult(json.loads(to_json(report)), tuple(written))
