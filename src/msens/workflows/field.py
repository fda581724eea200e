"""The field workflow: solve the field model of a study's MsS sensors and write its files.

``field.json`` (the model's numbers), ``field.vtu`` (ParaView), the bias-field map and a 3-D
view (:mod:`msens.field_outputs`), and a short text report of the coils, the beads near them
and the magnets' pull at their contacts.
"""

from __future__ import annotations

from pathlib import Path

from msens.config.study import Study
from msens.io.output import OutputDir
from msens.workflows.common import check_format

#: The files ``field`` writes (the map in the chosen figure format; the 3-D view PNG).
FIELD_OUTPUTS = ("field.json", "field.vtu", "field_B.png", "field_3d.png")


def field(study: Study, out: Path, *, fig_format: str = "png") -> str:
    """Solve the field model of the study's MsS sensors; write ``field.json``, ``field.vtu``
    and figures (the field map in ``fig_format``: png, pdf or svg; the 3-D view is always
    PNG) into ``out``; return a short text report.

    Raises
    ------
    InputError
        If the study has no MsS sensor, ``fig_format`` is not one msens writes, or ``out``
        holds user files of the same names.
    """
    from msens.config.fieldsetup import geometry_from_study
    from msens.field_outputs import write_field_outputs

    geometry = geometry_from_study(study)
    target = OutputDir(out)
    target.check([f"field_B.{check_format(fig_format)}" if n == "field_B.png" else n
                  for n in FIELD_OUTPUTS])
    report, seconds = _solve_timed(geometry)
    written = write_field_outputs(report, out, fig_format=fig_format, timings_s=seconds)
    for name, path in written.items():
        if not path.startswith("skipped"):
            target.record(name)
    return format_field(report, written, timings_s=seconds)


def _solve_timed(geometry):
    """:func:`msens.field.sensor_model.run_field_model`'s stages, each timed here (the
    physics keeps no clock): the report and ``field.json``'s ``timings_s`` (mesh,
    bias_solve, inductance, post; wall seconds)."""
    import logging

    from msens.field.sensor_model import bias_problem, coil_results, field_report, load_mesh
    from msens.field.solve import solve
    from msens.progress import heartbeat, stopwatch

    log = logging.getLogger(__name__)
    seconds: dict[str, float] = {}

    def stage(name, compute):
        elapsed = stopwatch()
        value = compute()
        seconds[name] = elapsed()
        return value

    log.info("field model: mesh (cached on disk) and nonlinear bias solve")
    with heartbeat(log, "field model: mesh and bias solve"):
        axi, path = stage("mesh", lambda: load_mesh(geometry))
        sol = stage("bias_solve", lambda: solve(bias_problem(geometry, axi)))
    log.info("field model: %d dofs, %d Newton iterations, %.1f s", sol.dofs, sol.iterations,
             seconds["mesh"] + seconds["bias_solve"])
    with heartbeat(log, "field model: coil inductances, bead fields, contact forces"):
        coils = stage("inductance", lambda: coil_results(sol, geometry))
        report = stage("post", lambda: field_report(geometry, sol, path, coils))
    return report, seconds


def format_field(report, written: dict[str, str], *,
                 timings_s: dict[str, float] | None = None) -> str:
    """Plain-text summary of a field-model report (of
    :func:`msens.field.sensor_model.run_field_model`) and of the files
    ``written`` (name: path, or why it was skipped); ``timings_s``: the stages' wall
    seconds as the caller measured them (the bias solve's is quoted when given)."""
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
