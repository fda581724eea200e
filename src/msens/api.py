"""Public Python API: load a study, run it, write and print its results.

The ``msens`` command is a thin layer over these functions, so scripts and notebooks get
exactly the numbers the terminal prints::

    import msens.api as ms
    study = ms.load("studies/paper-table2.toml")
    result = ms.run(study)
    result.rows()          # Table-2 rows as dicts
"""

from __future__ import annotations

from pathlib import Path

from msens.output import OutputDir
from msens.pipeline import StudyResult, run_study
from msens.study import Study, default_study_path, load_study


def load(path: str | Path) -> Study:
    """Read and validate a study file (raises :class:`msens.errors.InputError`)."""
    return load_study(path)


def load_default() -> Study:
    """The built-in default study."""
    return load_study(default_study_path())


def run(study: Study) -> StudyResult:
    """Calibrate, simulate and observe every setup of ``study``."""
    return run_study(study)


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
    return {
        "study": result.study.name,
        "source": result.study.source,
        "striker_velocity_m_per_s": result.study.striker.velocity_m_per_s,
        "calibration": calibration,
        "setups": static,
        "rows": result.rows(),
    }


FIGURES = ("contact_forces.png", "sensor_profiles.png", "sensor_records.png", "table2.png")


def prepare_outputs(out: str | Path, *, figures: bool = True) -> OutputDir:
    """Open ``out`` and check, before any work, that no user file would be overwritten."""
    d = OutputDir(out)
    d.check(["summary.json", *(FIGURES if figures else ())])
    return d


def write_outputs(result: StudyResult, out: str | Path | OutputDir, *,
                  figures: bool = True) -> list[Path]:
    """Write ``summary.json`` and the figures into ``out``; returns the written paths."""
    from msens import plots

    d = out if isinstance(out, OutputDir) else prepare_outputs(out, figures=figures)
    written = [d.write_json("summary.json", summary(result))]
    if figures:
        makers = dict(zip(FIGURES, (
            lambda: plots.contact_profiles(result),
            lambda: plots.sensor_profiles(result),
            lambda: plots.sensor_records(result),
            lambda: plots.table2(result.rows()),
        ), strict=True))
        for name, make in makers.items():
            fig = make()
            written.append(d.savefig(name, fig, dpi=150))
            plots.close(fig)
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
    names = [s.name for s in study.setups]
    name = setup or names[0]
    if name not in names:
        raise InputError(f"--setup must be one of {', '.join(names)}, got {name!r}")
    if out.exists():
        raise InputError(f"refusing to overwrite '{out}'")
    result = run_study(study)
    chosen = next(s for s in result.setups if s.setup.name == name)
    meta = {"study": study.name}
    if study.striker.drop_height_m is not None:
        meta["drop_height_m"] = repr(study.striker.drop_height_m)
    waveform = synthesize(chosen, RigEffects(shots=shots, noise=noise, seed=seed),
                          metadata=meta)
    write_waveform(waveform, out)
    return out


def compare(study: Study, data: Path, out: Path) -> tuple[dict, list[Path]]:
    """Compare measured ``data`` with the model of ``study``; write ``compare.json`` and an
    overlay figure into ``out``."""
    from msens import plots
    from msens.compare import compare as compare_records
    from msens.compare import match_setup, shot_records
    from msens.io.read import read_waveform

    target = OutputDir(out)
    target.check(["compare.json", "overlay.png"])
    waveform = read_waveform(data)
    result = run_study(study)
    report = compare_records(result, waveform)
    report["data"] = str(data)
    written = [target.write_json("compare.json", report)]
    setup = match_setup(result, waveform)
    fig = plots.overlay(setup, shot_records(setup, waveform))
    written.append(target.savefig("overlay.png", fig, dpi=150))
    plots.close(fig)
    return report, written


def format_comparison(report: dict) -> str:
    """Plain-text table of a comparison report."""
    head = f"{'channel':<10} {'K':>10} {'TOF us':>16} {'AR':>14} {'nRMSE':>7} {'corr':>6}"
    lines = [f"setup {report['setup']}, {report['shots']} shot(s)", head, "-" * len(head)]
    for ch in report["channels"]:
        m, s = ch["model"], ch["measured"]
        lines.append(
            f"{ch['channel']:<10} {s['gain']['mean']:>10.4g} "
            f"{s['tof_us']['mean']:>7.1f} ({m['tof_us']:>6.1f}) "
            f"{s['ar']['mean']:>6.3f} ({m['ar']:>5.3f}) {s['nrmse']['mean']:>7.4f} "
            f"{s['correlation']['mean']:>6.3f}")
    lines.append("(model values in parentheses)")
    return "\n".join(lines)


FIELD_OUTPUTS = ("field.json", "field.vtu", "field_B.png", "field_3d.png")


def field(study: Study, out: Path) -> str:
    """Solve the field model of the study's MsS sensors; write ``field.json``, ``field.vtu``
    and figures into ``out``; return a short text report."""
    from msens.field.report import write_field_outputs
    from msens.field.sensor_model import run_field_model
    from msens.fieldsetup import geometry_from_study

    geometry = geometry_from_study(study)
    target = OutputDir(out)
    target.check(list(FIELD_OUTPUTS))
    report = run_field_model(geometry)
    written = write_field_outputs(report, out)
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
           workers: int | None = None, progress: bool = True):
    """Sweep coil/magnet designs of the study's MsS (:mod:`msens.design`); writes
    ``designs.csv``, ``pareto.png`` and ``recommendation.json`` into ``out``."""
    from msens.design import load_sweep, run_design

    return run_design(study, load_sweep(sweep), out, scheduler=scheduler, workers=workers,
                      progress=progress)


def format_design(result) -> str:
    """Plain-text summary of a design sweep."""
    from msens.design import format_result

    return format_result(result)
