"""Graded triangular mesh of the upper-right quarter of a sphere's meridian section.

The section is the quarter disc ``r >= 0, z >= 0, r^2 + z^2 <= R^2`` in the (r, z) plane of
an axisymmetric model: its boundaries are the equator ``z = 0``, the axis ``r = 0`` and the
arc ``r^2 + z^2 = R^2``. The mesh coordinates are (r, s) with s = z - R measured from the
pole, so that the equator is s = -R: near the pole the elements are ~1e-4 R wide, and with
the origin at the sphere's centre rounding errors of the coordinates (1e-16 R) would be
large enough, relative to them, to stall skfem's inverse isoparametric mapping.

A mesh node is placed on the arc at the edge of the contact cap (``r = a``) so that no
element straddles the edge of a Hertz pressure, where the pressure has an infinite slope;
the element size grows linearly with distance from the pole, up to a bulk size.

gmsh places the mid-side nodes of second-order meshes on the true arc, so the quadratic
(``MeshTri2``) mesh represents the sphere up to an O(h^3) geometric error.
"""

from __future__ import annotations

from dataclasses import dataclass

import gmsh
import numpy as np
import skfem

from msens.errors import require
from msens.meshing import generate_sized

#: gmsh model name, so that we remove only our own model from a shared gmsh session.
_MODEL = "msens-bead-section"


@dataclass(frozen=True)
class BeadMeshSpec:
    """Element sizes of the bead section mesh, all relative to lengths of the problem.

    Attributes
    ----------
    contact_elements : float
        Elements across the contact radius at the pole: h_pole = a / contact_elements.
    grading : float
        Growth of the element size with distance d from the pole, dh/dd, dimensionless.
    bulk_size : float
        Largest element size as a fraction of the radius R.
    refine : int
        Uniform refinement level: every size above is divided by 2**refine, so the mesh
        width halves everywhere at each level (used for convergence studies).
    order : int
        Geometric order of the elements, 1 (straight sides) or 2 (curved, isoparametric).
    """

    contact_elements: float = 8.0
    grading: float = 0.2
    bulk_size: float = 0.0625
    refine: int = 0
    order: int = 2

    def __post_init__(self) -> None:
        require(self.contact_elements > 0,
                f"contact_elements must be > 0, got {self.contact_elements}")
        require(self.grading > 0, f"grading must be > 0, got {self.grading}")
        require(0 < self.bulk_size <= 1, f"bulk_size must be in (0, 1], got {self.bulk_size}")
        require(isinstance(self.refine, int) and 0 <= self.refine <= 8,
                f"refine must be an integer in 0..8, got {self.refine!r}")
        require(self.order in (1, 2), f"order must be 1 or 2, got {self.order!r}")


def bead_section_mesh(radius: float, contact_radius: float,
                      spec: BeadMeshSpec | None = None) -> skfem.MeshTri1:
    """Mesh the quarter meridian section of a sphere, graded toward the pole ``(0, R)``.

    Parameters
    ----------
    radius : float
        Sphere radius R, m.
    contact_radius : float
        Radius a of the loaded cap at the pole, m; 0 < a < R/2.
    spec : BeadMeshSpec, optional
        Element sizes; defaults to ``BeadMeshSpec()``.

    Returns
    -------
    skfem.MeshTri1 or skfem.MeshTri2
        Coordinates ``p`` of shape (2, n) are (r, s) in m with s = z - R (pole at the
        origin, equator at s = -R). Boundaries tagged ``"axis"``,
        ``"equator"``, ``"contact"`` (arc with r <= a) and ``"free"`` (rest of the arc).
    """
    spec = spec or BeadMeshSpec()
    require(radius > 0, f"radius must be > 0 m, got {radius}")
    require(0 < contact_radius < 0.5 * radius,
            f"contact radius must be in (0, R/2) = (0, {0.5 * radius:g}) m, "
            f"got {contact_radius}")
    alpha = contact_radius / radius  # everything in gmsh is in units of R
    scale = 2.0 ** (-spec.refine)
    h_pole = alpha / spec.contact_elements * scale
    h_bulk = spec.bulk_size * scale
    slope = spec.grading * scale

    own = not gmsh.isInitialized()
    if own:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add(_MODEL)
        geo = gmsh.model.geo
        o = geo.addPoint(0.0, -1.0, 0.0)
        eq = geo.addPoint(1.0, -1.0, 0.0)
        # s = sqrt(1 - alpha^2) - 1 without cancellation
        edge = geo.addPoint(alpha, -alpha**2 / (1.0 + np.sqrt(1.0 - alpha**2)), 0.0)
        pole = geo.addPoint(0.0, 0.0, 0.0)
        c_eq = geo.addLine(o, eq)
        c_free = geo.addCircleArc(eq, o, edge)
        c_contact = geo.addCircleArc(edge, o, pole)
        c_axis = geo.addLine(pole, o)
        loop = geo.addCurveLoop([c_eq, c_free, c_contact, c_axis])
        surf = geo.addPlaneSurface([loop])
        geo.synchronize()

        def size(dim, tag, x, y, z, lc):
            d = np.hypot(x, y)
            return min(h_bulk, h_pole + slope * d)

        generate_sized(size)
        if spec.order == 2:
            gmsh.model.mesh.setOrder(2)
        etype = 9 if spec.order == 2 else 2  # gmsh: 9 = 6-node triangle, 2 = 3-node
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, enodes = gmsh.model.mesh.getElementsByType(etype, surf)
    finally:
        if gmsh.model.getCurrent() == _MODEL:
            gmsh.model.remove()
        if own:
            gmsh.finalize()

    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    xy = coords.reshape(-1, 3)[:, :2] * radius
    nper = 6 if spec.order == 2 else 3
    t = index[enodes.astype(np.int64)].reshape(-1, nper)
    return _to_skfem(xy, t, spec.order, radius, contact_radius)


def _to_skfem(xy: np.ndarray, t: np.ndarray, order: int, radius: float,
              contact_radius: float) -> skfem.MeshTri1:
    """Build the skfem mesh from gmsh nodes and connectivity and tag its boundaries."""
    # drop nodes gmsh keeps for the geometry but no element uses (e.g. the centre point
    # is used; this is for safety), then renumber
    used = np.unique(t)
    renum = -np.ones(xy.shape[0], dtype=np.int64)
    renum[used] = np.arange(used.size)
    xy, t = xy[used], renum[t]
    # counter-clockwise orientation of the vertices (skfem expects positive Jacobians)
    v = xy[t[:, :3]]
    det = ((v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1])
           - (v[:, 2, 0] - v[:, 0, 0]) * (v[:, 1, 1] - v[:, 0, 1]))
    flip = det < 0
    if order == 1:
        t[flip] = t[flip][:, [0, 2, 1]]
        mesh = skfem.MeshTri1(xy.T.copy(), t.T.copy())
    else:
        # gmsh 6-node order: v0 v1 v2 m01 m12 m20; skfem MeshTri2 doflocs: vertices, then
        # edge midpoints in skfem's own edge numbering -> go through meshio's mapping
        t[flip] = t[flip][:, [0, 2, 1, 5, 4, 3]]
        import meshio
        from skfem.io.meshio import from_meshio

        mesh = from_meshio(meshio.Mesh(xy, [("triangle6", t)]))
    # facets are classified by their chord midpoints, among boundary facets only: the
    # axis and equator are exact straight lines, everything else is the arc; the chord
    # sag (< h^2 / 8R) is far smaller than the z-spacing of nodes near the contact edge
    tol = 1e-9 * radius
    edge_s = -contact_radius**2 / (radius + np.sqrt(radius**2 - contact_radius**2))

    def on_arc(x):
        return (x[0] > tol) & (x[1] > -radius + tol)

    return mesh.with_boundaries({
        "axis": lambda x: np.abs(x[0]) < tol,
        "equator": lambda x: np.abs(x[1] + radius) < tol,
        "contact": lambda x: on_arc(x) & (x[1] > edge_s),
        "free": lambda x: on_arc(x) & (x[1] < edge_s),
    })
