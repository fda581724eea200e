"""Public Python API: load a study, run it, write and print its results.

The ``msens`` command is a thin layer over these functions, so scripts and notebooks get
exactly the numbers the terminal prints::

    import msens.api as ms
    study = ms.load("studies/paper-table2.toml")
    result = ms.run(study)
    result.rows()          # Table-2 rows as dicts
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from msens.output import OutputDir
from msens.pipeline import StudyResult, run_study
from msens.study import PAPER_TABLE2, Study, builtin_study_path, default_study_path, load_study


def load(path: str | Path) -> Study:
    """Read and validate a study file (raises :class:`msens.errors.InputError`)."""
    return load_study(path)


def load_default() -> Study:
    """The built-in default study (the paper's MsS predicted from physics)."""
    return load_study(default_study_path())


def load_paper_table2() -> Study:
    """The paper's three setups (Table 2) with its Eq. 10 calibration."""
    return load_study(builtin_study_path(PAPER_TABLE2))


def replace(study: Study, changes: dict | None = None, /, **more) -> Study:
    """``study`` with keys changed by their dotted names, validated like a study file
    (:meth:`msens.study.Study.replace`): ``replace(study, {"sensor[1].coil.turns": 900})``."""
    return study.replace(changes, **more)


def run(study: Study) -> StudyResult:
    """Calibrate, simulate and observe every setup of ``study``."""
    return run_study(study)


def provenance(study: Study) -> dict:
    """What made a result file: the msens version and the study's content hash (SHA-256 of
    its canonical JSON form, so the same study gives the same hash wherever its file is)."""
    import hashlib
    import json

    from msens.cli import version
    from msens.design.cache import canonical

    text = json.dumps(canonical(dataclasses.replace(study, source="")), sort_keys=True,
                      separators=(",", ":"))
    return {"msens_version": version(),
            "study_sha256": hashlib.sha256(text.encode()).hexdigest()}


def summary(result: StudyResult) -> dict:
    """The content of ``summary.json``: study, calibrated parameters, Table-2 rows."""
    fit = result.fit
    calibration = {
        "gamma_contact_kg_per_s": result.gamma_contact,
        "gamma_wall_kg_per_s": result.gamma_wall,
        "fitted": fit is not None,
    }
    if fit is not None:
        calibration.update({
            "objective_eq10": fit.objective,
            "ar_top_model": fit.ar_top_model,
            "ar_bottom_model": fit.ar_bottom_model,
            "simulations": fit.n_simulations,
            "paper_gamma_contact_kg_per_s": 4.8,
            "paper_gamma_wall_kg_per_s": 0.0,
        })
    static = {
        s.setup.name: {
            "precompression": [{"contacts": [p.first, p.last], "force_N": p.force_n}
                               for p in s.setup.precompression],
        }
        for s in result.setups
    }
    out = {
        "study": result.study.name,
        "source": result.study.source,
        "provenance": provenance(result.study),
        "striker_velocity_m_per_s": result.study.striker.velocity_m_per_s,
        "calibration": calibration,
        "setups": static,
        "rows": result.rows(),
    }
    out.update(physics_summary(result))
    return out


def _trough(record) -> dict:
    """Is there a dip of the integrated signal before its main (incident) peak?"""
    f = record.weighted_force
    i_peak = int(np.argmax(f))
    before = f[:i_peak + 1]
    depth = float(-before.min()) if before.size else 0.0
    peak = float(f[i_peak])
    return {"present": bool(depth > 0.01 * peak), "depth_fraction_of_peak": depth / peak,
            "time_us": float(record.t[int(np.argmin(before))] * 1e6)}


def physics_summary(result: StudyResult) -> dict:
    """Physics-MsS part of ``summary.json``: per-coil voltage, each mechanism's share of the
    signal and sensitivity profile, the magnet's precompression per contact and the
    dominant transduction mechanism."""
    coils, villari, approach = [], 0.0, 0.0
    precompression = []
    for s in result.setups:
        if not s.transducers:
            continue
        from msens.electronics import resonance
        from msens.magnetics.transducer import magnetic_precompression

        magnetic = magnetic_precompression(s.transducers)
        for c, f in enumerate(np.cumsum(magnetic)[:-1], start=1):
            if abs(f) > 1e-3:
                precompression.append({"setup": s.setup.name, "contact": c, "upper": c,
                                       "lower": c + 1, "force_N": float(f)})
        for r in s.sensors:
            if r.mss is None:
                continue
            tr = s.transducers[r.sensor.particle]
            villari += float(np.sum(np.abs(tr.sensitivity_villari)))
            approach += float(np.sum(np.abs(tr.sensitivity_approach)))
            f0, q = resonance(r.mss.circuit)
            coils.append({
                "setup": s.setup.name, "particle": r.sensor.particle,
                "peak_voltage_V": float(np.max(np.abs(r.mss.voltage))),
                "peak_voltage_time_us": float(r.mss.t_daq[np.argmax(np.abs(r.mss.voltage))]
                                              * 1e6),
                "peak_emf_V": float(np.max(np.abs(r.mss.emf))),
                "resistance_ohm": tr.resistance_ohm, "inductance_H": tr.inductance_H,
                "resonance_Hz": f0, "quality_factor": q,
                "pre_peak_trough": _trough(r.mss),
                "mechanism_share": mechanism_share(tr, s.history),
                **({"frequency_response": frequency_summary(s.responses[r.sensor.particle],
                                                            tr)}
                   if s.responses else {}),
                "sensitivity_profile": [
                    {"contact": int(c), "dLambda_dF_Wb_per_N": float(v + g),
                     "villari_Wb_per_N": float(v), "approach_Wb_per_N": float(g)}
                    for c, v, g in zip(tr.contacts, tr.sensitivity_villari,
                                       tr.sensitivity_approach, strict=True)],
            })
    if not coils:
        return {}
    return {"coils": coils, "magnetic_precompression_N": precompression,
            "dominant_mechanism": "villari" if villari >= approach else "contact approach",
            "mechanism_magnitude_Wb_per_N": {"villari": villari, "approach": approach}}


def frequency_summary(response, tr) -> dict:
    """A coil's eddy-current frequency response for ``summary.json``: at each solved
    frequency, the contact-approach and Villari sensitivities of the two contacts beside the
    coil's bead relative to their static values (magnitude, phase in degrees), and the coil
    impedance as R (Ω) and L (H)."""
    freqs = np.asarray(response.frequencies, dtype=float)
    own = [int(np.flatnonzero(np.asarray(response.contacts) == c)[0])
           for c in (tr.particle - 1, tr.particle)]
    out = {"frequencies_Hz": freqs.tolist(), "contacts": [tr.particle - 1, tr.particle]}
    for name, values in (("approach", response.approach), ("villari", response.villari)):
        ratio = np.asarray(values)[:, own] / np.asarray(values)[0, own]
        out[f"{name}_ratio_magnitude"] = np.abs(ratio).tolist()
        out[f"{name}_ratio_phase_deg"] = np.degrees(np.angle(ratio)).tolist()
    z = np.asarray(response.impedance)
    out["resistance_ohm"] = z.real.tolist()
    out["inductance_H"] = np.asarray(response.inductance).real.tolist()
    return out


def mechanism_share(tr, history) -> dict:
    """Each mechanism's open-circuit EMF alone: its peak (V) and its share of the summed
    signal energy ∫EMF_m² dt / Σ_m ∫EMF_m² dt (the two are not orthogonal: their cross term
    is left out, so the shares add to 1)."""
    from msens.magnetics.transducer import contact_rates, emf_from_rates

    rates = contact_rates(history.t, history.force, tr.contacts, tr.contact_stiffness,
                          approach=history.approach)
    emfs = {m: emf_from_rates(rates, tr.sensitivity_villari, tr.dlambda_dapproach, m)
            for m in ("villari", "approach")}
    energy = {m: float(np.trapezoid(e**2, history.t)) for m, e in emfs.items()}
    total = sum(energy.values()) or 1.0
    return {m: {"peak_emf_V": float(np.max(np.abs(e))), "energy_share": energy[m] / total}
            for m, e in emfs.items()}


FIGURES = ("contact_forces.png", "sensor_profiles.png", "sensor_records.png", "table2.png")
PHYSICS_FIGURES = ("mss_voltage.png", "mss_integrated.png", "sensitivity_profile.png",
                   "magnetic_precompression.png", "field_B.png")


def _check_format(fig_format: str) -> str:
    """``fig_format`` if msens can write figures in it (:data:`msens.plots.FORMATS`)."""
    from msens.errors import InputError
    from msens.plots import FORMATS

    if fig_format not in FORMATS:
        raise InputError(f"--format must be one of {', '.join(FORMATS)}, got {fig_format!r}")
    return fig_format


def _figure_names(names, fig_format: str) -> list[str]:
    """Figure file names (listed as .png) in ``fig_format``."""
    from msens.output import figure_name

    return [figure_name(n, fig_format) if n.endswith(".png") else n for n in names]


def prepare_outputs(out: str | Path, *, figures: bool = True,
                    fig_format: str = "png") -> OutputDir:
    """Open ``out`` and check, before any work, that no user file would be overwritten.

    ``fig_format`` ("png", "pdf" or "svg") names the figures to check.
    """
    _check_format(fig_format)
    d = OutputDir(out)
    d.check(["summary.json",
             *(_figure_names(FIGURES + PHYSICS_FIGURES, fig_format) if figures else ())])
    return d


def _figure_makers(result: StudyResult) -> dict:
    from msens import plots

    makers = {
        "contact_forces.png": lambda: plots.contact_profiles(result),
        "sensor_records.png": lambda: plots.sensor_records(result),
    }
    if any(s.setup.inserts or len(result.setups) > 1 for s in result.setups):
        makers["sensor_profiles.png"] = lambda: plots.sensor_profiles(result)
    if result.study.reference:
        makers["table2.png"] = lambda: plots.table2(result.rows())
    if any(s.transducers for s in result.setups):
        makers["mss_voltage.png"] = lambda: plots.mss_voltages(result)
        makers["mss_integrated.png"] = lambda: plots.mss_integrated(result)
        makers["sensitivity_profile.png"] = lambda: plots.sensitivity_profile(result)
        makers["magnetic_precompression.png"] = lambda: plots.magnetic_precompression(result)
    return makers


def _field_map(result: StudyResult, d: OutputDir, fig_format: str = "png") -> Path | None:
    """The bias-field map of the first physics setup (re-solves the cached field model)."""
    from msens.field.report import plot_field_map
    from msens.field.sensor_model import run_field_model
    from msens.fieldsetup import geometry_from_study

    setup = next((s.setup for s in result.setups if s.transducers), None)
    if setup is None:
        return None
    report = run_field_model(geometry_from_study(result.study, setup), inductance=False)
    return d.write(f"field_B.{fig_format}", lambda p: plot_field_map(report, p, fig_format))


def write_outputs(result: StudyResult, out: str | Path | OutputDir, *,
                  figures: bool = True, fig_format: str = "png") -> list[Path]:
    """Write ``summary.json`` and the figures (in ``fig_format``: "png", "pdf" or "svg")
    into ``out``; returns the written paths."""
    from msens import plots

    _check_format(fig_format)
    d = out if isinstance(out, OutputDir) else prepare_outputs(out, figures=figures,
                                                               fig_format=fig_format)
    written = [d.write_json("summary.json", summary(result))]
    if figures:
        for name, make in _figure_makers(result).items():
            fig = make()
            written.append(d.savefig(name, fig, fmt=fig_format, dpi=plots.DPI))
            plots.close(fig)
        field_map = _field_map(result, d, fig_format)
        if field_map is not None:
            written.append(field_map)
    return written


def format_summary(result: StudyResult) -> str:
    """A short plain-text table of the rows, for the terminal."""
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


def synth(study: Study, out: Path, *, setup: str | None = None, shots: int = 1,
          noise: float = 0.01, seed: int = 0) -> Path:
    """Write synthetic measurements of one setup of ``study`` to ``out`` (never over a file)."""
    from msens.errors import InputError
    from msens.io.read import write_waveform
    from msens.synth import RigEffects, synthesize

    if shots < 1 or shots > 10000:
        raise InputError(f"--shots must be from 1 to 10000, got {shots}")
    if not 0.0 <= noise <= 1.0:
        raise InputError(f"--noise must be from 0 to 1 (fraction of the peak), got {noise}")
    if not 0 <= seed < 2**63:  # numpy's generators take non-negative seeds
        raise InputError(f"--seed must be from 0 to 2**63 - 1, got {seed}")
    names = [s.name for s in study.setups]
    name = setup or names[0]
    if name not in names:
        raise InputError(f"--setup must be one of {', '.join(names)}, got {name!r}")
    if out.exists():
        raise InputError(f"refusing to overwrite '{out}'")
    from msens import plausible

    chosen_setup = study.setup(name)
    samples = round(study.simulation.t_end_s * study.simulation.sample_rate_hz) + 1
    # the shots' records and the rig effects' working copies (about four) in float64
    need = 4 * 8 * shots * samples * len(chosen_setup.sensors)
    if need > plausible.MEMORY_BUDGET_BYTES:
        raise InputError(f"--shots {shots} of {samples:,} samples x "
                         f"{len(chosen_setup.sensors)} channels need about "
                         f"{need / 2**30:.3g} GiB; the budget is "
                         f"{plausible.MEMORY_BUDGET_BYTES / 2**30:g} GiB: fewer shots, or a "
                         "shorter 'simulation.t_end_s'")
    result = run_study(study)
    chosen = next(s for s in result.setups if s.setup.name == name)
    meta = {"study": study.name}
    if study.striker.drop_height_m is not None:
        meta["drop_height_m"] = repr(study.striker.drop_height_m)
    waveform = synthesize(chosen, RigEffects(shots=shots, noise=noise, seed=seed),
                          metadata=meta)
    write_waveform(waveform, out)
    return out


def compare(study: Study, data: Path, out: Path, *,
            fig_format: str = "png") -> tuple[dict, list[Path]]:
    """Compare measured ``data`` with the model of ``study``; write ``compare.json`` and an
    overlay figure (``overlay.<fig_format>``: png, pdf or svg) into ``out``.

    The data's unit and channels are checked against the study file before anything is
    simulated, so mismatched data fail in about a second instead of after the study's run.

    Raises
    ------
    InputError
        If ``out`` holds user files of the same names, the data's metadata give a unit
        other than V, no setup of the study has exactly the data's sensors, or a record
        has no pulse to compare.
    """
    from msens import plots
    from msens.compare import (
        check_signal,
        check_units,
        match_setup,
        match_setup_spec,
        shot_records,
    )
    from msens.compare import compare as compare_records
    from msens.io.read import read_waveform

    target = OutputDir(out)
    target.check(["compare.json", f"overlay.{_check_format(fig_format)}"])
    from msens.signalcheck import check_amplitudes, check_pulses, check_shots

    waveform = read_waveform(data)
    source = str(getattr(data, "path", data))
    check_units(waveform)
    match_setup_spec(study, waveform)
    check_shots(waveform, source)
    check_amplitudes(waveform, source)
    check_pulses(waveform, source)  # no signal is an error, in compare as in diagnose
    result = run_study(study)
    check_signal(match_setup(result, waveform), waveform, source)
    report = compare_records(result, waveform)
    report["data"] = str(data)
    report["provenance"] = provenance(study)
    written = [target.write_json("compare.json", report)]
    setup = match_setup(result, waveform)
    fig = plots.overlay(setup, shot_records(setup, waveform))
    written.append(target.savefig("overlay.png", fig, fmt=fig_format, dpi=plots.DPI))
    plots.close(fig)
    return report, written


def format_comparison(report: dict) -> str:
    """Plain-text table of a comparison report (the content of ``compare.json``).

    The conversion factor K is printed with its unit (``gain_unit``): N/V for bead and rod
    channels, N/(V s) for a four-contact MsS, V/V for a physics MsS. TOF and AR are those
    of the compared records (for a physics MsS, of its integrated DAQ voltage).
    """
    # K's unit follows its value in a column of its own: a channel's K is one quantity
    head = (f"{'channel':<10} {'K':>10} {'':<7} {'TOF us':>16} {'AR':>14} "
            f"{'nRMSE':>7} {'corr':>6}")
    lines = [f"setup {report['setup']}, {report['shots']} shot(s)", head, "-" * len(head)]
    for ch in report["channels"]:
        m, s = ch["model"], ch["measured"]
        lines.append(
            f"{ch['channel']:<10} {s['gain']['mean']:>10.4g} {ch.get('gain_unit', '?'):<7} "
            f"{s['tof_us']['mean']:>7.1f} ({m['tof_us']:>6.1f}) "
            f"{s['ar']['mean']:>6.3f} ({m['ar']:>5.3f}) {s['nrmse']['mean']:>7.4f} "
            f"{s['correlation']['mean']:>6.3f}")
    lines.append("(model values in parentheses)")
    return "\n".join(lines)


FIELD_OUTPUTS = ("field.json", "field.vtu", "field_B.png", "field_3d.png")


def field(study: Study, out: Path, *, fig_format: str = "png") -> str:
    """Solve the field model of the study's MsS sensors; write ``field.json``, ``field.vtu``
    and figures (the field map in ``fig_format``: png, pdf or svg; the 3-D view is always
    PNG) into ``out``; return a short text report."""
    from msens.field.report import write_field_outputs
    from msens.field.sensor_model import run_field_model
    from msens.fieldsetup import geometry_from_study

    geometry = geometry_from_study(study)
    target = OutputDir(out)
    target.check([f"field_B.{_check_format(fig_format)}" if n == "field_B.png" else n
                  for n in FIELD_OUTPUTS])
    report = run_field_model(geometry)
    written = write_field_outputs(report, out, fig_format=fig_format)
    for name, path in written.items():
        if not path.startswith("skipped"):
            target.record(name)
    return format_field(report, written)


def format_field(report, written: dict[str, str]) -> str:
    """Plain-text summary of a field-model report."""
    sensors = [u.coil.particle for u in report.geometry.sensors]
    near = {p + d for p in sensors for d in (-2, -1, 0, 1, 2)}
    lines = [f"field model: {report.dofs} dofs, {report.elements} elements, "
             f"{report.newton_iterations} Newton iterations, bias solve "
             f"{report.timings_s['bias_solve']:.1f} s",
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


def design(study: Study, sweep: str | Path, out: str | Path, *, scheduler: str | None = None,
           workers: int | None = None, progress: bool = True, fig_format: str = "png"):
    """Sweep coil/magnet designs of the study's MsS (:mod:`msens.design`); writes
    ``designs.csv``, ``pareto.<fig_format>`` and ``recommendation.json`` into ``out``."""
    from msens import budget
    from msens.design import load_sweep, run_design

    budget.check(study)
    return run_design(study, load_sweep(sweep), out, scheduler=scheduler, workers=workers,
                      progress=progress, provenance=provenance(study),
                      fig_format=_check_format(fig_format))


def format_design(result) -> str:
    """Plain-text summary of a design sweep."""
    from msens.design import format_result

    return format_result(result)


def diagnose(study: Study, data: Path | None, out: Path, *, reference: str | None = None,
             passes: int = 1, fig_format: str = "png") -> tuple[dict, list[Path]]:
    """Name the effect the model of ``study`` misses; write ``diagnosis.json`` and
    ``diagnosis.<fig_format>`` (png, pdf or svg) into ``out``.

    Either ``data`` (a measured waveform; its sensors choose the study's setup) or
    ``reference`` (a setup name: its ``[reference]`` rows are the measurement) is given.
    """
    import json

    from msens import budget
    from msens.diagnose import diagnose_passes, diagnose_reference
    from msens.diagnose.report import FILES
    from msens.diagnose.report import write as write_diagnosis
    from msens.errors import InputError
    from msens.io.read import read_waveform

    if (data is None) == (reference is None):
        raise InputError("diagnose needs either DATA (a waveform file) or --reference SETUP, "
                         "not both")
    if not 1 <= passes <= 7:
        raise InputError(f"--passes must be from 1 to 7, got {passes}")
    target = OutputDir(out)
    target.check(_figure_names(FILES, _check_format(fig_format)))
    budget.check(study)
    if data is not None:
        waveform = read_waveform(data)
        _check_measurement(study, waveform, str(getattr(data, "path", data)))
        results = diagnose_passes(waveform, study, passes=passes)
    else:
        results, added = [], []
        for _ in range(passes):
            d = diagnose_reference(study, reference, added=tuple(added))
            results.append(d)
            if d.effect == "none":
                break
            added.append((d.effect, d.parameters))
    written = write_diagnosis(results, target, provenance=provenance(study),
                              fig_format=fig_format)
    report = json.loads(written[0].read_text())
    return report, written


def _check_measurement(study: Study, waveform, source: str) -> None:
    """The checks ``compare`` makes on a measured waveform, for ``diagnose``: complete shots,
    plausible amplitudes, and records neither inverted nor time-scaled against the model
    (one model run, seconds)."""
    from msens.compare import check_signal, check_units, match_setup, match_setup_spec
    from msens.signalcheck import check_amplitudes, check_pulses, check_shots

    check_units(waveform)
    match_setup_spec(study, waveform)
    check_shots(waveform, source)
    check_amplitudes(waveform, source)
    check_pulses(waveform, source)
    check_signal(match_setup(run_study(study), waveform), waveform, source)


def format_diagnosis(report: dict) -> str:
    """Plain-text summary of ``diagnosis.json``."""
    lines = [f"setup {report['setup']} ({report['mode']}): disagreement mostly at the "
             f"{report['disagreement']['where']}",
             f"{'effect':<24} {'score (dBIC)':>13} {'misfit':>10}  parameters"]
    for c in report["candidates"]:
        pars = ", ".join(f"{k}={v:.4g}" for k, v in c["parameters"].items())
        lines.append(f"{c['effect']:<24} {c['score']:>13.1f} {c['misfit']:>10.4g}  {pars}")
    for i, p in enumerate(report["passes"], 1):
        pars = ", ".join(f"{k}={v:.4g}" for k, v in p["parameters"].items())
        lines.append(f"pass {i}: {p['effect']}" + (f" ({pars})" if pars else "")
                     + f"; misfit {p['misfit_before']:.4g} -> {p['misfit_after']:.4g}")
    return "\n".join(lines)
