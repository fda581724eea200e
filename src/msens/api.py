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

from msens import results
from msens.config.schema import PAPER_TABLE2
from msens.config.study import Study, builtin_study_path, default_study_path, load_study
from msens.io.output import DPI, OutputDir
from msens.pipeline import run_study
from msens.results import StudyResult
from msens.workflows.common import check_format as _check_format
from msens.workflows.common import figure_names as _figure_names
from msens.workflows.common import provenance
from msens.workflows.compare import compare as compare
from msens.workflows.compare import format_comparison as format_comparison
from msens.workflows.diagnose import diagnose as diagnose
from msens.workflows.diagnose import format_diagnosis as format_diagnosis


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
    (:meth:`msens.config.study.Study.replace`):
    ``replace(study, {"sensor[1].coil.turns": 900})``."""
    return study.replace(changes, **more)


def run(study: Study, *, scheduler: str | None = None) -> StudyResult:
    """Calibrate, simulate and observe every setup of ``study`` (the eddy-current frequency
    solves on the Dask cluster at ``scheduler`` when given)."""
    from msens import preflight

    # the address is checked even when no remote work turns out to be needed
    preflight.study(study)
    scheduler = preflight.check_scheduler(scheduler)
    return run_study(study, scheduler=scheduler)


def summary(result: StudyResult) -> dict:
    """The content of ``summary.json`` (:func:`msens.results.summary` with this run's
    provenance)."""
    return results.summary(result, provenance(result.study))


physics_summary = results.physics_summary
mechanism_share = results.mechanism_share
frequency_summary = results.frequency_summary


FIGURES = ("contact_forces.png", "sensor_profiles.png", "sensor_records.png", "table2.png")
PHYSICS_FIGURES = ("mss_voltage.png", "mss_integrated.png", "sensitivity_profile.png",
                   "magnetic_precompression.png", "field_B.png")


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
            written.append(d.savefig(name, fig, fmt=fig_format, dpi=DPI))
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
          noise: float = 0.01, seed: int = 0, overwrite: bool = False) -> Path:
    """Write synthetic measurements of one setup of ``study`` to ``out`` (never over an
    existing file unless ``overwrite``)."""
    from msens import preflight
    from msens.errors import InputError
    from msens.io.read import write_waveform
    from msens.synth import RigEffects, synthesize

    preflight.study(study)
    out = preflight.output_file(out, "--out", overwrite=overwrite)
    shots = preflight.count(shots, "--shots", 1, 10000)
    noise = preflight.number(noise, "--noise", 0.0, 1.0, " (fraction of the peak)")
    seed = preflight.count(seed, "--seed", 0, 2**63 - 1)
    if not 0 <= seed < 2**63:  # numpy's generators take non-negative seeds
        raise InputError(f"--seed must be from 0 to 2**63 - 1, got {seed}")
    names = [s.name for s in study.setups]
    name = setup or names[0]
    if name not in names:
        raise InputError(f"--setup must be one of {', '.join(names)}, got {name!r}")
    if out.exists() and not overwrite:
        raise InputError(f"refusing to overwrite '{out}' (the command's --overwrite replaces it)")
    from msens.config import plausible

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
    write_waveform(waveform, out, overwrite=overwrite)
    return out


FIELD_OUTPUTS = ("field.json", "field.vtu", "field_B.png", "field_3d.png")


def field(study: Study, out: Path, *, fig_format: str = "png") -> str:
    """Solve the field model of the study's MsS sensors; write ``field.json``, ``field.vtu``
    and figures (the field map in ``fig_format``: png, pdf or svg; the 3-D view is always
    PNG) into ``out``; return a short text report."""
    from msens.config.fieldsetup import geometry_from_study
    from msens.field.sensor_model import run_field_model
    from msens.field_outputs import write_field_outputs

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
    from msens import budget, preflight
    from msens.design import load_sweep, run_design

    preflight.study(study)
    scheduler = preflight.check_scheduler(scheduler)
    workers = preflight.check_workers(workers)
    out = preflight.output_dir(out)
    budget.check(study)
    return run_design(study, load_sweep(sweep), out, scheduler=scheduler, workers=workers,
                      progress=progress, provenance=provenance(study),
                      fig_format=_check_format(fig_format))


def format_design(result) -> str:
    """Plain-text summary of a design sweep."""
    from msens.design import format_result

    return format_result(result)
