"""Small gmsh (OpenCASCADE) meshes for the field-solver verification problems.

Each builder writes a .msh 4.1 file of the meridian half-plane (x = r >= 0, y = z) with named
2-D physical groups for the parts and the surrounding ``air``, and the 1-D group ``outer`` for
the truncation boundary (a half circle of radius ``r_out`` about the origin), then reads it
back with :func:`msens.field.mesh.read_gmsh`. Element size grows linearly with the distance
from the parts: ``h(d) = min(h_far, h_near + grading * d)``.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import gmsh
import numpy as np

from msens.errors import require
from msens.field.mesh import AxiMesh, read_gmsh
from msens.meshing import generate_sized


@dataclass(frozen=True)
class Part:
    """A named part: an axis-aligned rectangle or a disc centred on the axis (a half disc).

    Attributes
    ----------
    name : str
        Physical group name.
    kind : str
        ``"rect"`` (r0, r1, z0, z1) or ``"sphere"`` (radius, z centre).
    dims : tuple of float
        Dimensions, m.
    h : float
        Element size on and inside the part, m.
    """

    name: str
    kind: str
    dims: tuple[float, ...]
    h: float

    def distance(self, r: float, z: float) -> float:
        """Distance of (r, z) from the part (0 inside), m."""
        if self.kind == "rect":
            r0, r1, z0, z1 = self.dims
            dr = max(r0 - r, 0.0, r - r1)
            dz = max(z0 - z, 0.0, z - z1)
            return float(np.hypot(dr, dz))
        radius, zc = self.dims
        return max(float(np.hypot(r, z - zc)) - radius, 0.0)


def build_mesh(parts: Sequence[Part], r_out: float, h_far: float, grading: float = 0.3,
               path: str | Path | None = None, sizing: Sequence[Part] = ()) -> AxiMesh:
    """Mesh the parts inside a half-disc of air of radius ``r_out`` and read it back.

    Parameters
    ----------
    parts : sequence of Part
        Disjoint parts (touching is allowed).
    r_out : float
        Radius of the truncation half circle (group ``outer``), m.
    h_far : float
        Largest element size, m.
    grading : float
        Size growth per unit distance from the nearest part.
    path : str or Path, optional
        Where to write the .msh; a temporary file (removed afterwards) by default.
    sizing : sequence of Part
        Extra size-only zones (not geometry), e.g. a strip along the axis.
    """
    require(r_out > 0 and h_far > 0, "r_out and h_far must be > 0")
    # gmsh 4.15 rejects the "-noenv" flag with a warning; not reading the user's config files
    # has the same purpose (a reproducible mesh); interruptible=False allows worker threads
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("verification")
        occ = gmsh.model.occ
        box = occ.addRectangle(0.0, -r_out, 0.0, r_out, 2 * r_out)
        disc = occ.addDisk(0.0, 0.0, 0.0, r_out, r_out)
        domain, _ = occ.intersect([(2, disc)], [(2, box)])
        tags = []
        for p in parts:
            if p.kind == "rect":
                r0, r1, z0, z1 = p.dims
                tags.append(occ.addRectangle(r0, z0, 0.0, r1 - r0, z1 - z0))
            else:
                radius, zc = p.dims
                d = occ.addDisk(0.0, zc, 0.0, radius, radius)
                b = occ.addRectangle(0.0, zc - radius, 0.0, radius, 2 * radius)
                out, _ = occ.intersect([(2, d)], [(2, b)])
                tags.append(out[0][1])
        _, child = occ.fragment(domain, [(2, t) for t in tags])
        occ.synchronize()
        part_surfs = [[s for _, s in child[1 + i]] for i in range(len(parts))]
        taken = {s for ss in part_surfs for s in ss}
        air = [s for _, s in child[0] if s not in taken]
        for p, ss in zip(parts, part_surfs, strict=True):
            gmsh.model.addPhysicalGroup(2, ss, name=p.name)
        gmsh.model.addPhysicalGroup(2, air, name="air")
        all_surfs = [(2, s) for s in air + sorted(taken)]
        bnd = gmsh.model.getBoundary(all_surfs, combined=True, oriented=False)
        outer = []
        for _, c in bnd:
            # segments on the axis (r = 0) are not part of the truncation boundary
            x_mid = occ.getCenterOfMass(1, abs(c))[0]
            if x_mid > 1e-6 * r_out:
                outer.append(abs(c))
        gmsh.model.addPhysicalGroup(1, outer, name="outer")

        def size(dim, tag, x, y, z, lc):
            best = h_far
            for p in (*parts, *sizing):
                best = min(best, p.h + grading * p.distance(x, y))
            return best

        generate_sized(size)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        if path is None:
            fd, tmp = tempfile.mkstemp(suffix=".msh")
            os.close(fd)
            try:
                gmsh.write(tmp)
                return read_gmsh(tmp)
            finally:
                os.remove(tmp)
        gmsh.write(str(path))
        return read_gmsh(path)
    finally:
        gmsh.finalize()


def sphere_mesh(radius: float, r_out: float, h: float, h_far: float | None = None,
                name: str = "sphere") -> AxiMesh:
    """A sphere of ``radius`` centred at the origin in air (groups ``sphere``, ``air``)."""
    return build_mesh([Part(name, "sphere", (radius, 0.0), h)], r_out, h_far or r_out / 8)


def two_spheres_mesh(radius: float, distance: float, r_out: float, h: float,
                     h_far: float | None = None) -> AxiMesh:
    """Spheres ``lower`` (centre z = −d/2) and ``upper`` (z = +d/2) in air."""
    parts = [Part("lower", "sphere", (radius, -distance / 2), h),
             Part("upper", "sphere", (radius, distance / 2), h)]
    return build_mesh(parts, r_out, h_far or r_out / 8)


def rect_mesh(name: str, r0: float, r1: float, length: float, r_out: float, h: float,
              h_far: float | None = None) -> AxiMesh:
    """One rectangle r0 <= r <= r1, |z| <= length/2 (a winding or a ring magnet) in air."""
    part = Part(name, "rect", (r0, r1, -length / 2, length / 2), h)
    axis = Part("axis", "rect", (0.0, r0, -length, length), h)
    return build_mesh([part], r_out, h_far or r_out / 8, sizing=[axis])
