"""gmsh mesh of a sphere with a graded skin layer, for the eddy-current verification.

At 100 kHz the skin depth of 1018 steel (μ_r ~ 1000) is ~ 20 µm against a bead radius of
2.4 mm, so the field inside the sphere lives in a thin shell under its surface. The shell is
meshed as a *structured* layer, built here: ``rows`` rows of cells between concentric arcs,
the outermost row ``first`` thick and each row inward ``ratio`` times thicker, every
quadrilateral cell split into two triangles. Along the surface the cells are
``π R / arc_segments`` long: the field varies there on the scale of R (as sin θ, cos θ), so
the cells are thin and long (aspect ratios up to ~100) — harmless for the accuracy because
they are aligned with the layer, and the split cells (isosceles trapezoids) have no angle
above 90° + π/(2 arc_segments) (the maximum-angle condition holds). The core inside the
layer and the air are meshed by gmsh (algorithm 6) with ``arc_segments`` equal segments on
the two arcs bounding the layer, so the three parts conform.

Meridian half-plane: x = r >= 0, y = z, sphere centred at the origin; subdomains ``sphere``
(layer and core) and ``air``, boundary ``outer`` (the half circle of radius ``r_out`` about
the sphere's centre: the truncation boundary). Straight-sided triangles make the sphere a
polygon of revolution: a relative error ~ (π/arc_segments)²/3 in its moment (3e-4 at 96).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gmsh
import numpy as np

from msens.errors import internal, require
from msens.field.mesh import AxiMesh, facets_of_lines, from_arrays
from msens.meshing import generate_sized


@dataclass(frozen=True)
class SkinLayer:
    """Graded structured layer under a curved surface.

    Attributes
    ----------
    first : float
        Thickness of the row at the surface, m.
    ratio : float
        Thickness ratio of consecutive rows going inward (>= 1).
    rows : int
        Number of rows.
    arc_segments : int
        Cells along the half circle (the meridian of the sphere).
    """

    first: float
    ratio: float
    rows: int
    arc_segments: int

    def __post_init__(self) -> None:
        require(self.first > 0, f"SkinLayer.first must be > 0, got {self.first}")
        require(self.ratio >= 1.0, f"SkinLayer.ratio must be >= 1, got {self.ratio}")
        require(self.rows >= 1 and self.arc_segments >= 4,
                f"SkinLayer needs rows >= 1 and arc_segments >= 4, got {self.rows}, "
                f"{self.arc_segments}")

    @property
    def thickness(self) -> float:
        """Total thickness of the layer, m."""
        if self.ratio == 1.0:
            return self.first * self.rows
        return self.first * (self.ratio**self.rows - 1.0) / (self.ratio - 1.0)

    @property
    def last(self) -> float:
        """Thickness of the innermost row, m."""
        return self.first * self.ratio ** (self.rows - 1)


def skin_layer(radius: float, first: float, ratio: float = 1.3,
               arc_segments: int = 96) -> SkinLayer:
    """A layer whose rows grow from ``first`` until they match the core's element size.

    The core's element size is the arc spacing π R / ``arc_segments``; rows are added while
    the innermost row is thinner than that (so the layer blends into the core).

    Parameters
    ----------
    radius : float
        Sphere radius R, m.
    first : float
        Thickness of the outermost row, m (a fraction of the smallest skin depth).
    ratio : float
        Growth ratio of the row thickness inward.
    arc_segments : int
        Cells along the half circle.

    Returns
    -------
    SkinLayer
    """
    require(ratio > 1.0, f"skin_layer needs ratio > 1 (a graded layer), got {ratio}")
    h_core = math.pi * radius / arc_segments
    rows = 1 if first >= h_core else math.ceil(math.log(h_core / first) / math.log(ratio))
    layer = SkinLayer(first, ratio, max(rows, 1), arc_segments)
    require(layer.thickness < 0.5 * radius,
            f"skin layer {layer.thickness:.3g} m is too thick for radius {radius:.3g} m")
    return layer


def layered_sphere_mesh(radius: float, layer: SkinLayer, r_out: float,
                        h_far: float | None = None, grading: float = 0.25) -> AxiMesh:
    """Mesh a sphere (graded skin layer + unstructured core) in a half disc of air.

    gmsh meshes the core (r < R − t, t the layer thickness) and the air, with ``arc_segments``
    equal segments on both arcs bounding the layer; the layer is then filled here, row by
    row, with vertices on concentric arcs at the same angles. (gmsh's own transfinite
    surface was tried first: its interpolation on this C-shaped half annulus does not keep
    the rows concentric — at the equator the first row came out 66 µm deep instead of 3 µm.)

    Parameters
    ----------
    radius : float
        Sphere radius R, m (centred at the origin).
    layer : SkinLayer
        The structured layer under the sphere surface.
    r_out : float
        Radius of the outer half circle (group ``outer``), m; > R.
    h_far : float, optional
        Largest air element size, m (default r_out / 8).
    grading : float
        Air element size growth per unit distance from the sphere surface.

    Returns
    -------
    AxiMesh
        Subdomains ``sphere`` (layer and core) and ``air``; boundary ``outer``.
    """
    t = layer.thickness
    require(0 < t < radius < r_out, f"need 0 < layer thickness {t:.3g} < R {radius:.3g} "
            f"< r_out {r_out:.3g} (m)")
    h_far = h_far or r_out / 8
    n_arc = layer.arc_segments
    h_surf = math.pi * radius / n_arc
    h_core = math.pi * (radius - t) / n_arc
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("eddy_sphere")
        occ = gmsh.model.occ

        def half_disc(rad: float) -> tuple[int, int]:
            # one arc from -π/2 to π/2 (a disc cut by a rectangle would split the arc at
            # its seam); returns (surface, arc)
            arc = occ.addCircle(0.0, 0.0, 0.0, rad, angle1=-math.pi / 2, angle2=math.pi / 2)
            p_top = occ.addPoint(0.0, rad, 0.0)
            p_bot = occ.addPoint(0.0, -rad, 0.0)
            axis = occ.addLine(p_top, p_bot)
            return occ.addPlaneSurface([occ.addCurveLoop([arc, axis])]), arc

        domain, _ = half_disc(r_out)
        sphere, _ = half_disc(radius)
        core, _ = half_disc(radius - t)
        _, child = occ.fragment([(2, domain)], [(2, sphere), (2, core)])
        occ.synchronize()
        core_s = {s for _, s in child[2]}
        sphere_s = {s for _, s in child[1]}
        layer_s = sorted(sphere_s - core_s)
        air_s = sorted({s for _, s in child[0]} - sphere_s)
        internal(len(layer_s) == 1 and len(core_s) == 1 and len(air_s) == 1,
                 "internal: unexpected gmsh fragments of the layered sphere")
        arcs = {}
        for _, c in gmsh.model.getBoundary([(2, layer_s[0])], combined=False, oriented=False):
            com = occ.getCenterOfMass(1, abs(c))
            if com[0] > 1e-9 * radius:
                arcs["outer" if com[0] > (radius - t / 2) * 2 / math.pi else "inner"] = abs(c)
        outer = []
        for _, c in gmsh.model.getBoundary([(2, air_s[0])], combined=False, oriented=False):
            com = occ.getCenterOfMass(1, abs(c))
            if math.hypot(com[0], com[1]) > 0.5 * (radius + r_out) and com[0] > 1e-9 * r_out:
                outer.append(abs(c))
        internal(len(arcs) == 2 and len(outer) == 1,
                 "internal: could not identify the layer arcs and the outer boundary")
        for c in arcs.values():
            gmsh.model.mesh.setTransfiniteCurve(c, n_arc + 1)
        occ.remove([(2, layer_s[0])])  # filled below; its bounding curves stay
        occ.synchronize()

        def size(dim, tag, x, y, z, lc):
            d = math.hypot(x, y)
            if d < radius - 0.5 * t:
                return h_core
            return min(h_far, h_surf + grading * max(d - radius, 0.0))

        generate_sized(size)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        xy = coords.reshape(-1, 3)[:, :2]
        index = {int(g): k for k, g in enumerate(tags)}

        def triangles(surf: int) -> np.ndarray:
            types, _, nodes = gmsh.model.mesh.getElements(2, surf)
            internal(list(types) == [2], "internal: gmsh made non-triangle elements")
            return np.array([index[int(g)] for g in nodes[0]], dtype=np.int64).reshape(-1, 3)

        def arc_nodes(curve: int) -> np.ndarray:
            ntags, _, _ = gmsh.model.mesh.getNodes(1, curve, includeBoundary=True)
            ids = np.unique([index[int(g)] for g in ntags])
            return ids[np.argsort(np.arctan2(xy[ids, 1], xy[ids, 0]))]

        tri_core, tri_air = triangles(next(iter(core_s))), triangles(air_s[0])
        ring_out, ring_in = arc_nodes(arcs["outer"]), arc_nodes(arcs["inner"])
        internal(ring_out.size == n_arc + 1 and ring_in.size == n_arc + 1,
                 "internal: the layer arcs do not have arc_segments + 1 nodes")
        _, _, lines = gmsh.model.mesh.getElements(1, outer[0])
        outer_lines = np.array([index[int(g)] for g in lines[0]], dtype=np.int64).reshape(-1, 2)
    finally:
        gmsh.finalize()
    return _assemble_layered_mesh(xy, tri_core, tri_air, ring_out, ring_in, outer_lines,
                                  radius, layer)


def _assemble_layered_mesh(xy: np.ndarray, tri_core: np.ndarray, tri_air: np.ndarray,
                           ring_out: np.ndarray, ring_in: np.ndarray, outer_lines: np.ndarray,
                           radius: float, layer: SkinLayer) -> AxiMesh:
    """Add the layer's interior rows and cells to gmsh's core and air meshes."""
    n_arc, rows = layer.arc_segments, layer.rows
    theta = np.arctan2(xy[ring_out, 1], xy[ring_out, 0])
    depth = layer.first * np.cumsum(layer.ratio ** np.arange(rows - 1))
    rho = radius - depth  # interior rows 1..rows-1
    new = np.stack([np.outer(rho, np.cos(theta)), np.outer(rho, np.sin(theta))], axis=-1)
    new[:, [0, -1], 0] = 0.0  # the axis ends exactly at r = 0
    n0 = xy.shape[0]
    grid = np.empty((rows + 1, n_arc + 1), dtype=np.int64)
    grid[0], grid[rows] = ring_out, ring_in
    grid[1:rows] = n0 + np.arange((rows - 1) * (n_arc + 1)).reshape(rows - 1, n_arc + 1)
    pts = np.vstack([xy, new.reshape(-1, 2)])
    a, b = grid[:-1, :-1], grid[:-1, 1:]  # row j (outer), angles i, i+1
    c, d = grid[1:, 1:], grid[1:, :-1]    # row j+1 (inner)
    # mirror-symmetric diagonals about the equator (the split quads have no obtuse angle)
    upper = (0.5 * (theta[:-1] + theta[1:]) > 0)[None, :]
    t1 = np.where(upper[..., None], np.stack([a, b, c], -1), np.stack([a, b, d], -1))
    t2 = np.where(upper[..., None], np.stack([a, c, d], -1), np.stack([b, c, d], -1))
    tri_layer = np.vstack([t1.reshape(-1, 3), t2.reshape(-1, 3)])
    tri = np.vstack([tri_core, tri_layer, tri_air])
    used = np.unique(tri)
    renum = -np.ones(pts.shape[0], dtype=np.int64)
    renum[used] = np.arange(used.size)
    n_sphere = tri_core.shape[0] + tri_layer.shape[0]
    subs = {"sphere": np.arange(n_sphere), "air": np.arange(n_sphere, tri.shape[0])}
    axi = from_arrays(pts[used].T, renum[tri].T, subs)
    facets = facets_of_lines(axi.mesh, renum[outer_lines].T)
    return from_arrays(axi.mesh.p, axi.mesh.t, subs, {"outer": np.unique(facets)})


def layer_profile(mesh: AxiMesh, radius: float) -> np.ndarray:
    """Depths below the sphere surface of the mesh vertices on the upper axis, m.

    A diagnostic of the layer grading: sorted R − z of the vertices with r = 0 and
    0 < z <= R, shape (k,) (the first ``layer.rows + 1`` are the layer's row boundaries).
    """
    p = mesh.mesh.p
    on_axis = (p[0] <= 1e-12) & (p[1] > 0) & (p[1] <= radius * (1 + 1e-12))
    return np.sort(radius - p[1, on_axis])
