"""Low-level gmsh steps shared by every mesh msens builds (the field model's, a bead's).

Placed below :mod:`msens.mechanics` and :mod:`msens.field` in the import order so that both
use it.
"""

from __future__ import annotations

from collections.abc import Callable


def generate_sized(size: Callable[..., float]) -> None:
    """Mesh the current gmsh model in 2-D with the element sizes of ``size`` alone.

    ``size(dim, tag, x, y, z, lc)`` returns the element size (m) at a point; sizes from the
    boundary, the points and the curvature are switched off so that it alone decides, and
    the Frontal-Delaunay algorithm (6) gives well-shaped triangles.
    """
    import gmsh

    gmsh.model.mesh.setSizeCallback(size)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.model.mesh.generate(2)
