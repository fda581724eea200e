"""The field workflow: solve the field model of a study's MsS sensors and write its files.

``field.json`` (the model's numbers), ``field.vtu`` (ParaView), the bias-field map and a 3-D
view (:mod:`msens.field_outputs`), returned as a :class:`FieldResult` whose text table
(:func:`msens.tables.format_field`) reports the coils, the beads near them and the magnets'
pull at their contacts.
"""

from __future__ import annotations

import copy
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from msens.config.study import Study
from msens.io.output import OutputDir
from msens.tables import format_field as format_field
from msens.workflows.common import check_format

if TYPE_CHECKING:
    from msens.field.sensor_model import FieldReport

#: The files ``field`` writes (the map in the chosen figure format; the 3-D view PNG).
FIELD_OUTPUTS = ("field.json", "field.vtu", "field_B.png", "field_3d.png")


@dataclass(frozen=True)
class FieldResult:
    """What ``field`` produced: the field model, its numbers and the files written.

    Attributes
    ----------
    model : FieldReport
        The solved model: mesh sizes, the coils (resistance, inductances), the beads' flux
        density and the contacts' magnetic compression (SI units).
    report : dict
        The content of ``field.json``; read it through :meth:`to_json`, which returns a copy.
    written : dict of str to str
        File name: path written, or why it was skipped (``"skipped: ..."``, the 3-D view
        without a working off-screen renderer).
    timings_s : dict of str to float
        Wall seconds of the stages (mesh, bias_solve, inductance, post).
    """

    model: FieldReport
    report: dict
    written: dict[str, str]
    timings_s: dict[str, float]

    @property
    def files(self) -> tuple[Path, ...]:
        """The files written."""
        return tuple(Path(v) for v in self.written.values() if not v.startswith("skipped"))

    @property
    def figures(self) -> tuple[Path, ...]:
        """The figures written (the field map, the 3-D view where it could be rendered)."""
        return tuple(p for p in self.files if p.suffix not in (".json", ".vtu"))

    def to_json(self) -> dict:
        """The content of ``field.json`` (a copy)."""
        return copy.deepcopy(self.report)

    def table(self) -> str:
        """What ``msens field`` prints (:func:`format_field`): the model's size and bias-solve
        time, the coils, the beads and contacts near them, the files written."""
        return format_field(self.model, self.written, timings_s=self.timings_s)


def field(study: Study, out: Path, *, fig_format: str = "png") -> FieldResult:
    """Solve the field model of the study's MsS sensors; write ``field.json``, ``field.vtu``
    and figures (the field map in ``fig_format``: png, pdf or svg; the 3-D view is always
    PNG) into ``out``.

    Returns
    -------
    FieldResult
        The model, the content of ``field.json`` (:meth:`FieldResult.to_json`), the text
        report (:meth:`FieldResult.table`) and the files written.

    Raises
    ------
    InputError
        If the study has no MsS sensor, ``fig_format`` is not one msens writes, or ``out``
        holds user files of the same names.
    """
    from msens.config.fieldsetup import geometry_from_study
    from msens.field_outputs import write_field_outputs
    from msens.progress import heartbeat

    geometry = geometry_from_study(study)
    target = OutputDir(out)
    target.check([f"field_B.{check_format(fig_format)}" if n == "field_B.png" else n
                  for n in FIELD_OUTPUTS])
    report, seconds = _solve_timed(geometry)
    log = logging.getLogger(__name__)
    log.info("field: writing field.json, field.vtu, the field map and the 3-D view to %s", out)
    with heartbeat(log, "field: writing the files and figures"):
        written = write_field_outputs(report, out, fig_format=fig_format, timings_s=seconds)
    for name, path in written.items():
        if not path.startswith("skipped"):
            target.record(name)
    data = json.loads(Path(written["field.json"]).read_text(encoding="utf-8"))
    return FieldResult(report, data, dict(written), dict(seconds))


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
