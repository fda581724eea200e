"""The text tables the commands print, in one place.

Each function turns a workflow's result (or the content of the JSON file it writes) into
the plain text the ``msens`` command prints; the result types call them from their
``table()`` methods (:meth:`msens.results.StudyResult.table`,
:class:`msens.workflows.compare.CompareResult`, ...). They only read what they are given:
nothing here runs a model, imports a numerical library or writes a file.

- :func:`format_summary` — a run's rows (``msens run``);
- :func:`format_comparison`, :func:`processing_line` — a comparison (``compare.json``);
- :func:`format_diagnosis` — a diagnosis (``diagnosis.json``);
- :func:`format_field` — the field model and the files written (``msens field``);
- :func:`format_design` — a design sweep's counts and recommendation (``msens design``);
- :func:`files_line` — the closing ``wrote ...`` line of compare and diagnose.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from os import PathLike
from typing import Any

__all__ = ["files_line", "format_comparison", "format_design", "format_diagnosis",
           "format_field", "format_summary", "processing_line"]


def files_line(paths: Iterable[str | PathLike[str]]) -> str:
    """``wrote a, b, ...``: the files a command wrote, as given (no folder resolved)."""
    return f"wrote {', '.join(str(p) for p in paths)}"


def format_summary(result: Any) -> str:
    """A short plain-text table of a run's rows, for the terminal.

    Parameters
    ----------
    result : msens.results.StudyResult
        Its study's name, the damping coefficients (kg/s), whether they were fitted, and
        :meth:`~msens.results.StudyResult.rows` (TOF in µs, peak force in N, speed in m/s).
    """
    lines = [f"study {result.study.name}: gamma_c = {result.gamma_contact:.3g} kg/s, "
             f"gamma_w = {result.gamma_wall:.3g} kg/s"
             + (" (fitted, paper Eq. 10)" if result.fit is not None else "")]
    head = f"{'setup':<6} {'pos':<7} {'part':>4} {'TOF us':>8} {'AR':>6} {'peak N':>7} " \
           f"{'speed m/s':>9} {'exp TOF':>8} {'exp AR':>6}"
    lines += [head, "-" * len(head)]
    for r in result.rows():
        ref = r.get("reference", {})
        lines.append(
            f"{r['setup']:<6} {r['position']:<7} {r['particle']:>4} {r['tof_us']:>8.1f} "
            f"{r['ar']:>6.3f} {r['incident_peak_N']:>7.2f} {r['speed_m_per_s']:>9.1f} "
            f"{ref.get('experiment_tof_us', float('nan')):>8.1f} "
            f"{ref.get('experiment_ar', float('nan')):>6.2f}")
    return "\n".join(lines)


def processing_line(report: Mapping) -> str:
    """The table line naming what compare does to the model that ``msens run`` does not,
    with the largest change it makes to a TOF (µs) and to the speed (m/s)."""
    tof = max((abs(ch["model"]["tof_us"] - ch["run"]["tof_us"]) for ch in report["channels"]),
              default=0.0)
    text = f"{report['model_processing']['description']} (changes a TOF by {tof:.2g} us"
    speed = report.get("speed")
    if speed is not None:
        text += (f", the speed by {abs(speed['model_m_per_s'] - speed['run_m_per_s']):.2g} "
                 "m/s")
    return text + ")"


def format_comparison(report: Mapping) -> str:
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


def format_diagnosis(report: Mapping) -> str:
    """Plain-text summary of ``diagnosis.json``: the candidates with their scores, each pass
    and the verdict."""
    lines = [f"setup {report['setup']} ({report['mode']}): disagreement mostly at the "
             f"{report['disagreement']['where']}",
             f"{'effect':<24} {'score (dBIC)':>13} {'misfit':>10}  parameters"]
    for c in report["candidates"]:
        pars = _parameters_text(c["parameters"], c.get("intervals", {}))
        flag = ("" if c.get("plausible", True) else "  [implausible]") + \
            ("" if c.get("significant", True) else
             "  [near floor]" if c.get("near_floor") else "  [below floor]") + \
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
    if any(c.get("near_floor") for c in report["candidates"]):
        lines.append("[near floor]: beyond its floor, but the floor is inside its interval's "
                     "model uncertainty (a chi^2 rise to it of at most the threshold): a "
                     "negligible change, not named")
    return "\n".join(lines)


def _parameters_text(parameters: Mapping, intervals: Mapping) -> str:
    """``name=value [lo, hi]`` per parameter (the interval where there is one)."""
    out = []
    for k, v in parameters.items():
        iv = intervals.get(k) or {}
        lo, hi = iv.get("lower"), iv.get("upper")
        out.append(f"{k}={v:.4g}" + (f" [{lo:.4g}, {hi:.4g}]" if lo is not None
                                      and hi is not None else ""))
    return ", ".join(out)


def format_field(report: Any, written: Mapping[str, str], *,
                 timings_s: Mapping[str, float] | None = None) -> str:
    """Plain-text summary of a field model and of the files written.

    Parameters
    ----------
    report : msens.field.sensor_model.FieldReport
        The model: its sizes, the coils (resistance in Ω, inductances in H), the beads
        (flux density at their centres, T) and the contacts (magnetic compression, N); the
        beads and contacts within two particles of a coil are listed.
    written : mapping of str to str
        File name: path, or why it was skipped (``"skipped: ..."``).
    timings_s : mapping of str to float, optional
        The stages' wall seconds as the caller measured them (the bias solve's is quoted
        when given).
    """
    sensors = [u.coil.particle for u in report.geometry.sensors]
    near = {p + d for p in sensors for d in (-2, -1, 0, 1, 2)}
    lines = [f"field model: {report.dofs} dofs, {report.elements} elements, "
             f"{report.newton_iterations} Newton iterations"
             + ("" if not timings_s or "bias_solve" not in timings_s
                else f", bias solve {timings_s['bias_solve']:.1f} s"),
             "NOTE: the bias magnet is an axisymmetric equivalent of the undocumented "
             "bridge magnet", "", "coil  R (Ohm)  L_air (mH)  L_bias (mH)"]
    for c in report.coils:
        l_air, l_bias = c.air_core_inductance_H * 1e3, c.inductance_H * 1e3
        lines.append(f"{c.particle:>4}  {c.resistance_ohm:>7.2f}  {l_air:>10.2f}  {l_bias:>11.2f}")
    lines += ["", "bead  Bz centre (T)"]
    lines += [f"{b.particle:>4}  {b.B_center_T[1]:>13.3f}" for b in report.beads
              if b.particle in near]
    lines += ["", "contact  magnetic compression (N)"]
    lines += [f"{c.upper:>3}-{c.lower:<3}  {c.magnetic_force_N:>10.2f}" for c in report.contacts
              if c.upper in near and c.lower in near]
    lines += ["", "wrote " + ", ".join(f"{k} ({v})" if v.startswith("skipped") else k
                                     for k, v in written.items())]
    return "\n".join(lines)


def format_design(result: Any) -> str:
    """Short text summary of a design sweep for the terminal: the counts, the recommended
    design and why (or why none), and the files written.

    Parameters
    ----------
    result : msens.design.DesignResult
    """
    rec = result.recommendation
    lines = [f"{result.kind} sweep: {result.designs} designs ({result.failed} failed, "
             f"{result.computed} computed, {result.designs - result.computed} from cache)"]
    if rec.get("design") is None:
        lines.append("no recommended design: " + "; ".join(rec["reasons"]))
    else:
        pars = ", ".join(f"{k}={v}" for k, v in rec["parameters"].items())
        lines.append(f"recommended design {rec['design']}: {pars}")
        lines.extend(f"  - {r}" for r in rec["reasons"])
    lines.append(files_line(result.files))
    return "\n".join(lines)
