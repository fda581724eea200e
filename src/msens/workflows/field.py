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
    from msens.field.sensor_model import run_field_model
    from msens.field_outputs import write_field_outputs

    geometry = geometry_from_study(study)
    target = OutputDir(out)
    target.check([f"field_B.{check_format(fig_format)}" if n == "field_B.png" else n
                  for n in FIELD_OUTPUTS])
    report = run_field_model(geometry)
    written = write_field_outputs(report, out, fig_format=fig_format)
    for name, path in written.items():
        if not path.startswith("skipped"):
            target.record(name)
    return format_field(report, written)


def format_field(report, written: dict[str, str]) -> str:
    """Plain-text summary of a field-model report (of
    :func:`msens.field.sensor_model.run_field_model`) and of the files
    ``written`` (name: path, or why it was skipped)."""
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
