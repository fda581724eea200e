"""Mesh a :class:`~msens.field.geometry.SensorGeometry` with gmsh (OpenCASCADE kernel).

The (r, z) half-plane model is built from its parts (truncated bead discs, coil and magnet
rectangles, the air box), fragmented so that the mesh is conforming at every interface, and
written as gmsh 4.1 ``.msh`` with named physical groups:

- surfaces: ``bead_<k>``, ``coil_<k>``, ``magnet_<k>``, ``pole_<k>_lower``,
  ``pole_<k>_upper`` (k = particle number) and ``air``;
- curves: ``axis`` (r = 0), ``outer`` (r = radius and the two z ends of the box) and
  ``contact_<k>_<k+1>`` (the flat shared by neighbour beads; only when they touch).

Grading: near a contact the air wedge between two spheres is only g + (rho^2 - a^2)/R thick
(g = optional gap between the flats), so the element size follows that height (times
``MeshOptions.wedge_factor``) from ``flat_fraction x a`` at the flat up to the bead size; beads,
coils and magnets get their own sizes; the far air grows to ``far_size``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import gmsh

from msens.errors import require
from msens.field.geometry import Rect, SensorGeometry


@dataclass(frozen=True)
class MeshOptions:
    """Mesh sizes (metres or fractions).

    Attributes
    ----------
    flat_fraction : float
        Element size at a contact flat as a fraction of the flat radius.
    wedge_factor : float
        Element size near a contact = this x the local air-gap height of the wedge.
    bead_size : float
        Element size inside and on the beads, m.
    part_size : float
        Element size in coils, magnets and pole pieces, m.
    far_size : float
        Largest element size in the far air, m.
    growth : float
        Distance over which sizes blend into ``far_size``, as a multiple of the part size.
    """

    flat_fraction: float = 0.4
    wedge_factor: float = 2.0
    bead_size: float = 0.4e-3
    part_size: float = 1.2e-3
    far_size: float = 8e-3
    growth: float = 6.0

    def __post_init__(self) -> None:
        for name in ("flat_fraction", "wedge_factor", "bead_size", "part_size", "far_size",
                     "growth"):
            v = getattr(self, name)
            require(v > 0 and math.isfinite(v), f"MeshOptions.{name} must be > 0, got {v}")


#: The OCC model is built in millimetres (OCC's tolerance, 1e-7 model units, would swallow the
#: 0.1 um caps that the contact flats cut off the beads if we worked in metres); gmsh scales the
#: saved mesh back to metres with Mesh.ScalingFactor.
MM = 1e3


def _bead_surface(occ, r: float, zc: float, h: float) -> int:
    """Bead disc (r >= 0 half) truncated to |z - zc| <= h (mm); returns the OCC surface tag."""
    disk = occ.addDisk(0.0, zc, 0.0, r, r)
    box = occ.addRectangle(0.0, zc - h, 0.0, r, 2 * h)
    out, _ = occ.intersect([(2, disk)], [(2, box)])
    if len(out) != 1:
        raise RuntimeError("internal: bead truncation gave more than one surface")
    return out[0][1]


def _rect_surface(occ, q: Rect) -> int:
    return occ.addRectangle(MM * q.r0, MM * q.z0, 0.0, MM * (q.r1 - q.r0), MM * (q.z1 - q.z0))


def _set_sizes(geometry: SensorGeometry, options: MeshOptions, part_rects: list[Rect]) -> None:
    """Size fields: contact wedges, bead column, parts, far air (combined by Min)."""
    f = gmsh.model.mesh.field
    b = geometry.beads
    a, big_r = MM * b.flat_radius, MM * b.radius
    bead_size, part_size, far_size = (MM * options.bead_size, MM * options.part_size,
                                      MM * options.far_size)
    fields: list[int] = []

    # Contact wedges: distance d from the flat's rim; gap ~ ((a + d)^2 - a^2)/R.
    rim_points = []
    for upper, _ in b.contacts:
        z = MM * b.contact_z(upper)
        rim_points.append(gmsh.model.occ.addPoint(a, z, 0.0))
    gmsh.model.occ.synchronize()
    if rim_points:
        dist = f.add("Distance")
        f.setNumbers(dist, "PointsList", rim_points)
        wedge = f.add("MathEval")
        gap = MM * b.contact_gap
        s_min = options.flat_fraction * a
        if gap > 0:  # an air gap between the flats must be resolved across its height
            s_min = min(s_min, options.wedge_factor * gap)
        # No upper clamp: the field grows quadratically and the other fields take over.
        expr = (f"Max({s_min!r}, {options.wedge_factor!r} * "
                f"({gap!r} + (2 * {a!r} * F{dist} + F{dist}^2) / {big_r!r}))")
        f.setString(wedge, "F", expr)
        fields.append(wedge)

    z0, z1 = (MM * z for z in b.z_span)
    column = f.add("Box")
    f.setNumber(column, "VIn", bead_size)
    f.setNumber(column, "VOut", far_size)
    f.setNumber(column, "XMin", 0.0)
    f.setNumber(column, "XMax", big_r * 1.05)
    f.setNumber(column, "YMin", z0 - 0.05 * big_r)
    f.setNumber(column, "YMax", z1 + 0.05 * big_r)
    f.setNumber(column, "Thickness", options.growth * part_size)
    fields.append(column)

    for q in part_rects:
        bx = f.add("Box")
        f.setNumber(bx, "VIn", part_size)
        f.setNumber(bx, "VOut", far_size)
        f.setNumber(bx, "XMin", MM * q.r0)
        f.setNumber(bx, "XMax", MM * q.r1)
        f.setNumber(bx, "YMin", MM * q.z0)
        f.setNumber(bx, "YMax", MM * q.z1)
        f.setNumber(bx, "Thickness", options.growth * part_size)
        fields.append(bx)

    lo = f.add("Min")
    f.setNumbers(lo, "FieldsList", fields)
    f.setAsBackgroundMesh(lo)


def build_mesh(geometry: SensorGeometry, path: str | Path,
               options: MeshOptions | None = None) -> Path:
    """Mesh the geometry and write a gmsh 4.1 ``.msh`` file.

    Parameters
    ----------
    geometry : SensorGeometry
    path : str or Path
        Output file (parent directory must exist). Written directly; callers wanting an
        atomic write pass a temporary name (see :mod:`msens.field.cache`).
    options : MeshOptions, optional

    Returns
    -------
    Path
        ``path``.
    """
    options = options or MeshOptions()
    path = Path(path)
    b = geometry.beads
    own = not gmsh.isInitialized()
    if own:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("msens-sensor")
        occ = gmsh.model.occ

        named: list[tuple[str, int]] = []
        for p in b.particles:
            named.append((f"bead_{p}", _bead_surface(occ, MM * b.radius, MM * b.center(p),
                                                     MM * b.half_height)))
        part_rects: list[Rect] = []
        for unit in geometry.iter_units():
            rects = [geometry.coil_rect(unit), *geometry.magnet_rects(unit)]
            part_rects.extend(rects)
            named.extend((q.name, _rect_surface(occ, q)) for q in rects)
        box = geometry.box()
        box_tag = _rect_surface(occ, box)

        _, out_map = occ.fragment([(2, box_tag)], [(2, t) for _, t in named])
        occ.synchronize()
        part_children = {name: [t for d, t in out_map[i + 1] if d == 2]
                         for i, (name, _) in enumerate(named)}
        taken = {t for ts in part_children.values() for t in ts}
        air = [t for d, t in out_map[0] if d == 2 and t not in taken]
        if not air:
            raise RuntimeError("internal: no air left after fragmenting the model")

        for name, tags in part_children.items():
            if not tags:
                raise RuntimeError(f"internal: part {name} vanished in fragmenting")
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        gmsh.model.addPhysicalGroup(2, air, name="air")

        eps = 1e-6  # mm; far below the 1e-4 mm bead caps
        z0, z1, r1 = MM * box.z0, MM * box.z1, MM * box.r1
        axis = [t for _, t in gmsh.model.getEntitiesInBoundingBox(
            -eps, z0 - eps, -1, eps, z1 + eps, 1, dim=1)]
        gmsh.model.addPhysicalGroup(1, axis, name="axis")
        outer = set()
        for bb in ((r1 - eps, z0 - eps, r1 + eps, z1 + eps),
                   (-eps, z0 - eps, r1 + eps, z0 + eps),
                   (-eps, z1 - eps, r1 + eps, z1 + eps)):
            outer |= {t for _, t in gmsh.model.getEntitiesInBoundingBox(
                bb[0], bb[1], -1, bb[2], bb[3], 1, dim=1)}
        gmsh.model.addPhysicalGroup(1, sorted(outer), name="outer")
        if b.contact_gap == 0:
            a = MM * b.flat_radius
            for upper, lower in b.contacts:
                z = MM * b.contact_z(upper)
                flat = [t for _, t in gmsh.model.getEntitiesInBoundingBox(
                    -eps, z - eps, -1, a + eps, z + eps, 1, dim=1)]
                if len(flat) != 1:
                    raise RuntimeError(f"internal: contact {upper}-{lower} flat not found")
                gmsh.model.addPhysicalGroup(1, flat, name=f"contact_{upper}_{lower}")

        _set_sizes(geometry, options, part_rects)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.model.mesh.generate(2)
        gmsh.option.setNumber("Mesh.ScalingFactor", 1 / MM)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.write(str(path))
    finally:
        if gmsh.model.getCurrent() == "msens-sensor":
            gmsh.model.remove()
        if own:
            gmsh.finalize()
    return path
