"""Axisymmetric magnetostatic finite-element model (coil, bias magnet, steel beads).

Core API (see the modules for details):

- :mod:`.mesh`: :class:`AxiMesh`, :func:`read_gmsh`, :func:`refined`
- :mod:`.regions`: :class:`Air`, :class:`LinearMagnetic`, :class:`NonlinearSoft`,
  :class:`PermanentMagnet`, :class:`CurrentRegion`
- :mod:`.solve`: :class:`MagnetostaticProblem`, ``solve.solve``, :func:`incremental`,
  :class:`FieldSolution`, :class:`FieldSolveError` (``solve`` itself is not re-exported
  here: it would shadow the submodule ``msens.field.solve``)
- :mod:`.post`: :func:`flux_density`, :func:`field_strength`, :func:`flux_linkage`,
  :func:`force_z`, :func:`energy`
- :mod:`.verify`: :func:`run_all`, :func:`format_table`
"""

from msens.field.mesh import AxiMesh, read_gmsh, refined
from msens.field.post import (
    energy,
    field_strength,
    flux_density,
    flux_linkage,
    force_z,
    potential_energy,
)
from msens.field.regions import Air, CurrentRegion, LinearMagnetic, NonlinearSoft, PermanentMagnet
from msens.field.solve import (
    FieldSolution,
    FieldSolveError,
    MagnetostaticProblem,
    incremental,
)

__all__ = [
    "Air",
    "AxiMesh",
    "CurrentRegion",
    "FieldSolution",
    "FieldSolveError",
    "LinearMagnetic",
    "MagnetostaticProblem",
    "NonlinearSoft",
    "PermanentMagnet",
    "energy",
    "field_strength",
    "flux_density",
    "flux_linkage",
    "force_z",
    "incremental",
    "potential_energy",
    "read_gmsh",
    "refined",
]
