"""Axisymmetric triangle meshes with named subdomains and boundaries.

The meridian half-plane is meshed with x = r >= 0 and y = z (metres). Meshes come from gmsh
(.msh 4.1, read through meshio); 2-D physical groups name the subdomains, 1-D physical groups
the boundaries.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np
import skfem

from msens.errors import InputError, require


@dataclass(frozen=True)
class AxiMesh:
    """A meridian-plane triangle mesh with named parts.

    Attributes
    ----------
    mesh : skfem.MeshTri
        Linear triangles, x = r (m, >= 0), y = z (m).
    subdomains : Mapping[str, ndarray]
        Element indices (int, shape (k,)) per 2-D physical group name; disjoint, covering all.
    boundaries : Mapping[str, ndarray]
        Facet indices (int, shape (k,)) per 1-D physical group name.
    """

    mesh: skfem.MeshTri
    subdomains: Mapping[str, np.ndarray]
    boundaries: Mapping[str, np.ndarray]

    @property
    def n_elements(self) -> int:
        """Number of triangles."""
        return int(self.mesh.t.shape[1])


def from_arrays(points: np.ndarray, triangles: np.ndarray, subdomains: Mapping[str, np.ndarray],
                boundaries: Mapping[str, np.ndarray] | None = None) -> AxiMesh:
    """Build an :class:`AxiMesh` from vertex and triangle arrays.

    Parameters
    ----------
    points : ndarray, shape (2, n)
        Vertex coordinates (r, z), m.
    triangles : ndarray, shape (3, m)
        Vertex indices per triangle (any orientation; skfem sorts them).
    subdomains : Mapping[str, ndarray]
        Element indices per name; must partition ``range(m)``.
    boundaries : Mapping[str, ndarray], optional
        Facet indices (of the resulting skfem mesh) per name.
    """
    p = np.asarray(points, dtype=float)
    t = np.asarray(triangles, dtype=np.int64).copy()
    require(p.ndim == 2 and p.shape[0] == 2, "mesh points must have shape (2, n)")
    require(float(p[0].min()) > -1e-12 * max(1.0, float(np.ptp(p[0]))),
            f"mesh has vertices at r < 0 (min r = {p[0].min():.3e} m); the meridian "
            "half-plane must have r >= 0")
    p[0] = np.maximum(p[0], 0.0)
    # skfem sorts the vertices of each triangle and integrates with |det J|: orientation is free
    d = ((p[0, t[1]] - p[0, t[0]]) * (p[1, t[2]] - p[1, t[0]])
         - (p[0, t[2]] - p[0, t[0]]) * (p[1, t[1]] - p[1, t[0]]))
    require(bool(np.all(d != 0.0)), "mesh has degenerate (zero-area) triangles")
    subs = {name: np.asarray(ix, dtype=np.int64) for name, ix in subdomains.items()}
    counts = np.zeros(t.shape[1], dtype=np.int64)
    for ix in subs.values():
        np.add.at(counts, ix, 1)
    require(bool(np.all(counts == 1)),
            f"subdomains must cover every triangle exactly once ({int(np.sum(counts == 0))} "
            f"uncovered, {int(np.sum(counts > 1))} in several)")
    bnds = {name: np.asarray(ix, dtype=np.int64) for name, ix in (boundaries or {}).items()}
    mesh = skfem.MeshTri(np.ascontiguousarray(p), np.ascontiguousarray(t), _subdomains=subs,
                         _boundaries=bnds or None)
    return AxiMesh(mesh=mesh, subdomains=subs, boundaries=bnds)


def facets_of_lines(mesh: skfem.MeshTri, lines: np.ndarray) -> np.ndarray:
    """Facet indices of ``mesh`` matching vertex pairs ``lines`` (shape (2, k)).

    Raises
    ------
    msens.errors.InputError
        If a line is not an edge of the mesh.
    """
    n = mesh.p.shape[1]
    keys = np.sort(mesh.facets, axis=0)
    fkey = keys[0].astype(np.int64) * n + keys[1]
    order = np.argsort(fkey)
    lk = np.sort(np.asarray(lines), axis=0)
    lkey = lk[0].astype(np.int64) * n + lk[1]
    pos = np.searchsorted(fkey, lkey, sorter=order)
    pos = np.minimum(pos, fkey.size - 1)
    found = fkey[order[pos]] == lkey
    require(bool(np.all(found)), f"{int(np.sum(~found))} boundary lines are not mesh edges")
    return order[pos]


def read_gmsh(path: str | Path) -> AxiMesh:
    """Read a 2-D gmsh mesh (.msh, format 4.1) with named physical groups.

    Parameters
    ----------
    path : str or Path
        The .msh file: linear triangles in the z = 0 plane with x = r >= 0, y = z (m); every
        triangle in exactly one named 2-D physical group; boundary lines in 1-D groups.

    Returns
    -------
    AxiMesh

    Raises
    ------
    msens.errors.InputError
        If the file is missing, unreadable, or has unnamed/quadratic/uncovered elements.
    """
    path = Path(path)
    require(path.is_file(), f"mesh file '{path}' does not exist")
    try:
        raw = meshio.read(path, file_format="gmsh")
    except (Exception, SystemExit) as exc:  # meshio raises many errors, even SystemExit
        raise InputError(f"mesh file '{path}' could not be read as gmsh: {exc}") from exc
    names = {(int(tag), int(dim)): name for name, (tag, dim) in raw.field_data.items()}
    phys = raw.cell_data.get("gmsh:physical")
    require(phys is not None, f"mesh file '{path}' has no physical groups")
    tri_blocks, line_blocks = [], []
    for block, tags in zip(raw.cells, phys, strict=True):
        require(block.type not in ("triangle6", "line3"),
                f"mesh file '{path}': use linear (order-1) elements; found {block.type}")
        if block.type == "triangle":
            tri_blocks.append((block.data, tags))
        elif block.type == "line":
            line_blocks.append((block.data, tags))
    require(bool(tri_blocks), f"mesh file '{path}' has no triangles")
    tri = np.vstack([d for d, _ in tri_blocks])
    tri_tag = np.concatenate([g for _, g in tri_blocks]).astype(int)
    used = np.unique(tri)
    renum = -np.ones(raw.points.shape[0], dtype=np.int64)
    renum[used] = np.arange(used.size)
    points = raw.points[used, :2].T
    subdomains = {}
    for tag in np.unique(tri_tag):
        name = names.get((int(tag), 2))
        require(name is not None, f"mesh file '{path}': 2-D physical group {tag} has no name")
        subdomains[name] = np.flatnonzero(tri_tag == tag)
    axi = from_arrays(points, renum[tri.T], subdomains)
    boundaries = {}
    if line_blocks:
        lines = np.vstack([d for d, _ in line_blocks])
        line_tag = np.concatenate([g for _, g in line_blocks]).astype(int)
        require(bool(np.all(renum[lines] >= 0)),
                f"mesh file '{path}': boundary lines use vertices of no triangle")
        for tag in np.unique(line_tag):
            name = names.get((int(tag), 1))
            require(name is not None,
                    f"mesh file '{path}': 1-D physical group {tag} has no name")
            sel = renum[lines[line_tag == tag]].T
            boundaries[name] = np.unique(facets_of_lines(axi.mesh, sel))
    return from_arrays(axi.mesh.p, axi.mesh.t, subdomains, boundaries)


def refined(axi: AxiMesh, times: int = 1) -> AxiMesh:
    """Uniformly refine (each triangle into four), keeping named subdomains and boundaries."""
    m = axi.mesh
    for _ in range(times):
        m = m.refined()
    subs = dict(m.subdomains or {})
    bnds = dict(m.boundaries or {})
    return AxiMesh(mesh=m, subdomains=subs, boundaries=bnds)


def axis_facets(mesh: skfem.MeshTri, rtol: float = 1e-9) -> np.ndarray:
    """Boundary facets lying on the axis r = 0 (both vertices at r <= rtol * mesh size)."""
    tol = rtol * max(float(np.ptp(mesh.p[0])), float(np.ptp(mesh.p[1])))
    bf = mesh.boundary_facets()
    on = np.all(mesh.p[0, mesh.facets[:, bf]] <= tol, axis=0)
    return bf[on]


def element_region_index(axi: AxiMesh, names: list[str]) -> np.ndarray:
    """Index into ``names`` of the subdomain of each element, shape (n_elements,)."""
    out = -np.ones(axi.n_elements, dtype=np.int64)
    for i, name in enumerate(names):
        out[axi.subdomains[name]] = i
    return out
