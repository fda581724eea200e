"""The compare workflow: a measured waveform against the model of a study.

The measurement is checked against the study file first (unit, channels, complete shots,
plausible amplitudes, a pulse in every record), so mismatched data fail in about a second,
then once more against the model's run (records neither inverted nor time-scaled). The same
checks open a diagnosis (:func:`check_measurement`). The comparison itself is
:func:`msens.compare.compare`; this module writes ``compare.json`` and the overlay figure
and formats the text table.
"""

from __future__ import annotations

from pathlib import Path

from msens import budget
from msens.compare import (
    check_signal,
    check_units,
    match_setup,
    match_setup_spec,
    processing_line,
    shot_records,
)
from msens.compare import compare as compare_records
from msens.config.study import Study
from msens.io.output import DPI, OutputDir
from msens.io.waveform import Waveform
from msens.pipeline import run_study
from msens.results import StudyResult
from msens.signals.signalcheck import check_amplitudes, check_pulses, check_shots
from msens.workflows.common import check_format, figure_names, provenance

#: The files ``compare`` writes (the overlay in the chosen figure format).
FILES = ("compare.json", "overlay.png")


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


def compare(study: Study, data: Path, out: Path, *,
            fig_format: str = "png") -> tuple[dict, list[Path]]:
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
    report : dict
        The content of ``compare.json``.
    written : list of Path
        The files written.

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
    return report, written


def format_comparison(report: dict) -> str:
    """Plain-text table of a comparison report (the content of ``compare.json``).

    The conversion factor K (paper Eq. 11, model per measured volt: the inverse of the
    gain ``gain_measured_per_model``) is printed with its unit (``K_unit``): N/V for bead and
    rod channels, N/(V s) for a four-contact MsS, V/V for a physics MsS. TOF and AR are those
    of the compared records (for a physics MsS, of its integrated DAQ voltage).
    """
    # K's unit follows its value in a column of its own: a channel's K is one quantity
    head = (f"{'channel':<10} {'K':>10} {'':<7} {'TOF us':>16} {'AR':>14} "
            f"{'nRMSE':>7} {'corr':>6}")
    lines = [f"setup {report['setup']}, {report['shots']} shot(s)", head, "-" * len(head)]
    for ch in report["channels"]:
        m, s = ch["model"], ch["measured"]
        lines.append(
            f"{ch['channel']:<10} {s['conversion_factor_K']['mean']:>10.4g} "
            f"{ch.get('K_unit', '?'):<7} "
            f"{s['tof_us']['mean']:>7.1f} ({m['tof_us']:>6.1f}) "
            f"{s['ar']['mean']:>6.3f} ({m['ar']:>5.3f}) {s['nrmse']['mean']:>7.4f} "
            f"{s['correlation']['mean']:>6.3f}")
    lines.append("(model values in parentheses)")
    if "model_processing" in report:
        lines.append(processing_line(report))
    return "\n".join(lines)
