"""The diagnose workflow: name the effect the model of a study misses, from a measurement.

The measurement is either a waveform file (checked as :mod:`msens.workflows.compare` checks
it; its sensors choose the setup) or the ``[reference]`` rows of one setup of the study.
Each pass fits the candidate effects of :mod:`msens.diagnose` and adds the best one; the
passes stop when none is needed. The workflow writes ``diagnosis.json`` and its figure
(:mod:`msens.diagnose.report`) and formats the text table.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from msens import budget
from msens.config.study import Study
from msens.errors import InputError
from msens.io.output import OutputDir
from msens.workflows.common import check_format, figure_names, provenance
from msens.workflows.compare import check_measurement

if TYPE_CHECKING:
    from msens.diagnose import Diagnosis

#: Most passes a diagnosis makes.
MAX_PASSES = 7


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
             passes: int = 1, fig_format: str = "png") -> tuple[dict, list[Path]]:
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
    report : dict
        The content of ``diagnosis.json``.
    written : list of Path
        The files written.

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
    return report, written


def format_diagnosis(report: dict) -> str:
    """Plain-text summary of ``diagnosis.json``: the candidates with their scores, each pass
    and the verdict."""
    lines = [f"setup {report['setup']} ({report['mode']}): disagreement mostly at the "
             f"{report['disagreement']['where']}",
             f"{'effect':<24} {'score (dBIC)':>13} {'misfit':>10}  parameters"]
    for c in report["candidates"]:
        pars = _parameters_text(c["parameters"], c.get("intervals", {}))
        flag = ("" if c.get("plausible", True) else "  [implausible]") + \
            ("" if c.get("significant", True) else "  [below floor]") + \
            ("  [at bound]" if c.get("at_bound") else "")
        lines.append(f"{c['effect']:<24} {c['score']:>13.1f} {c['misfit']:>10.4g}  {pars}"
                     + flag)
    for i, p in enumerate(report["passes"], 1):
        pars = _parameters_text(p["parameters"], p.get("parameter_intervals", {}))
        lines.append(f"pass {i}: {p['effect']}" + (f" ({pars})" if pars else "")
                     + f"; misfit {p['misfit_before']:.4g} -> {p['misfit_after']:.4g}; "
                     + ("explained" if p.get("explained") else "NOT explained"))
    if "summary" in report["passes"][-1]:
        lines.append(f"verdict: {report['passes'][-1]['summary']}")
    mu = (report.get("noise") or {}).get("model_uncertainty")
    if mu and mu.get("model_uncertainty_share", 0.0) > 0.0:
        lines.append(f"the residual is measured against the noise ({100 * mu['noise_share']:.0f} "
                     f"% of the variance) and the model's own uncertainty "
                     f"({100 * mu['model_uncertainty_share']:.0f} %)")
    if any(c.get("intervals") for c in report["candidates"]):
        lines.append("[lo, hi]: 95 % interval from the curvature of the fit; [at bound]: the "
                     "fit sits at an end of its searched range and is not named")
    return "\n".join(lines)


def _parameters_text(parameters: dict, intervals: dict) -> str:
    """``name=value [lo, hi]`` per parameter (the interval where there is one)."""
    out = []
    for k, v in parameters.items():
        iv = intervals.get(k) or {}
        lo, hi = iv.get("lower"), iv.get("upper")
        out.append(f"{k}={v:.4g}" + (f" [{lo:.4g}, {hi:.4g}]" if lo is not None
                                      and hi is not None else ""))
    return ", ".join(out)
