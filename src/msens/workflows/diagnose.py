"""The diagnose workflow: name the effect the model of a study misses, from a measurement.

The measurement is either a waveform file (checked as :mod:`msens.workflows.compare` checks
it; its sensors choose the setup) or the ``[reference]`` rows of one setup of the study.
Each pass fits the candidate effects of :mod:`msens.diagnose` and adds the best one; the
passes stop when none is needed. The workflow writes ``diagnosis.json`` and its figure
(:mod:`msens.diagnose.report`) and returns them as a :class:`DiagnoseResult` (its text
table: :func:`msens.tables.format_diagnosis`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from msens import budget
from msens.config.study import Study
from msens.errors import InputError
from msens.io.output import OutputDir
from msens.results import JsonReport
from msens.tables import files_line
from msens.tables import format_diagnosis as format_diagnosis
from msens.workflows.common import check_format, figure_names, provenance
from msens.workflows.compare import check_measurement

if TYPE_CHECKING:
    from msens.diagnose import Diagnosis

#: Most passes a diagnosis makes.
MAX_PASSES = 7


@dataclass(frozen=True)
class DiagnoseResult(JsonReport):
    """What ``diagnose`` produced: the passes, the report and the files written.

    Attributes
    ----------
    report : dict
        The content of ``diagnosis.json`` (the candidates with their scores, each pass, the
        verdict); read it through :meth:`to_json`, which returns a copy.
    passes : tuple of Diagnosis
        Each pass's diagnosis, in order (:class:`msens.diagnose.Diagnosis`).
    written : tuple of Path
        The files written: ``diagnosis.json``, then its figure (also :attr:`files`;
        :attr:`figures` the figure alone).
    """

    report: dict
    passes: tuple[Diagnosis, ...]
    written: tuple[Path, ...]

    def table(self) -> str:
        """What ``msens diagnose`` prints: the table (:func:`format_diagnosis`) and the
        files written."""
        return f"{format_diagnosis(self.report)}\n\n{files_line(self.files)}"


def reference_passes(study: Study, reference: str, passes: int) -> list[Diagnosis]:
    """Up to ``passes`` passes against the ``[reference]`` rows of setup ``reference``, each
    with the effects of the earlier ones added; stops after a pass that names none."""
    from msens.diagnose import diagnose_reference

    results: list[Diagnosis] = []
    added: list[tuple[str, dict]] = []
    for _ in range(passes):
        d = diagnose_reference(study, reference, added=tuple(added))
        results.append(d)
        if d.effect == "none":
            break
        added.append((d.effect, d.parameters))
    return results


def diagnose(study: Study, data: Path | None, out: Path, *, reference: str | None = None,
             passes: int = 1, fig_format: str = "png") -> DiagnoseResult:
    """Name the effect the model of ``study`` misses; write ``diagnosis.json`` and
    ``diagnosis.<fig_format>`` (png, pdf or svg) into ``out``.

    Parameters
    ----------
    study : Study
    data : Path or None
        A measured waveform (its sensors choose the study's setup); or None with
        ``reference``.
    out : Path
        Output folder; files of the same names that msens did not write are never
        overwritten.
    reference : str, optional
        A setup name: its ``[reference]`` rows are the measurement.
    passes : int
        Most passes, 1 to :data:`MAX_PASSES`.
    fig_format : {"png", "pdf", "svg"}

    Returns
    -------
    DiagnoseResult
        The passes, the content of ``diagnosis.json`` (:meth:`DiagnoseResult.to_json`), the
        text table (:meth:`DiagnoseResult.table`) and the files written.

    Raises
    ------
    InputError
        Neither or both of ``data`` and ``reference``, passes out of range, user files in
        ``out``, a study beyond the run budget, or data that do not match the study.
    """
    # the diagnosis library loads when a diagnosis runs (seconds), not with msens.api
    from msens.diagnose import diagnose_passes
    from msens.diagnose.report import FILES
    from msens.diagnose.report import write as write_diagnosis
    from msens.io.read import read_waveform

    if (data is None) == (reference is None):
        raise InputError("diagnose needs either DATA (a waveform file) or --reference SETUP, "
                         "not both")
    if not 1 <= passes <= MAX_PASSES:
        raise InputError(f"--passes must be from 1 to {MAX_PASSES}, got {passes}")
    target = OutputDir(out)
    target.check(figure_names(FILES, check_format(fig_format)))
    budget.check(study)
    if data is not None:
        waveform = read_waveform(data)
        check_measurement(study, waveform, str(getattr(data, "path", data)))
        results = diagnose_passes(waveform, study, passes=passes)
    else:
        results = reference_passes(study, reference, passes)
    written = write_diagnosis(results, target, provenance=provenance(study),
                              fig_format=fig_format)
    report = json.loads(written[0].read_text())
    return DiagnoseResult(report, tuple(results), tuple(written))
