"""Mesh a :class:`~msens.field.geometry.SensorGeometry` with gmsh (OpenCASCADE kernel).

The (r, z) half-plane model is built from its parts (truncated bead discs, coil and magnet
rectangles, the air box), fragmented so that the mesh is conforming at every interface, and
written as gmsh 4.1 ``.msh`` with named physical groups:

- surfaces: ``bead_<k>``, ``coil_<k>``, ``magnet_<k>``, ``pole_<k>_lower``,
  ``pole_<k>_upper`` (k = particle number) and ``air``;
- curves: ``axis`` (r = 0), ``outer`` (r = radius and the two z ends of the box) and
  ``contact_<k>_<k+1>`` (the flat shared by neighbour beads; only when they touch);
- with a contact layer (:attr:`~msens.field.geometry.BeadChain.contact_layer`), the surface
  ``layer_<k>_<k+1>`` between that contact's flats (its flats are not named ``contact_``).

Grading: near a contact the air wedge between two spheres is only g + (rho^2 - a^2)/R thick
(g = optional gap between the flats), so the element size follows that height (times
``MeshOptions.wedge_factor``) from ``flat_fraction x a`` at the flat up to the bead size; beads,
coils and magnets get their own sizes; the far air grows to ``far_size``. For the eddy-current
model (``MeshOptions.skin_size``) one rule grades the mesh into the skin of every conducting
part (the beads near a coil, the pole pieces, the magnets): size s + g·d at distance d from the
part's surface, s from :func:`skin_surface_size`.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import gmsh

from msens.errors import internal, require
from msens.field.geometry import Rect, SensorGeometry

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class MeshOptions:
    """Mesh sizes (metres or fractions).

    Attributes
    ----------
    flat_fraction : float
        Element size at a contact flat as a fraction of the flat radius.
    wedge_factor : float
        Element size near a contact = this x the local air-gap height of the wedge.
    near_contacts : int
        Contacts within this many beads of a coil's particle get the sizes above; contacts
        farther away are ``far_contact_factor`` times coarser (they matter less to the
        sensors' fields and forces).
    far_contact_factor : float
    bead_size : float
        Element size inside and on the beads, m.
    centre_size : float
        Element size at the bead centres (where B is reported), m.
    part_size : float
        Element size in coils, magnets and pole pieces, m.
    far_size : float
        Element size in the air next to the parts, m.
    far_growth : float
        Far-air element size grows as this fraction of the distance from the parts, so a
        large air box costs few elements.
    growth : float
        Distance over which part sizes blend into the air size, as a multiple of part_size.
    skin_size : float or None
        Element size at the surface of every conducting part, m: the beads within
        ``near_contacts`` of a coil, the pole pieces and the magnets
        (:func:`skin_surface_size`), growing linearly with the distance d from the surface
        as size + skin_growth·d (both sides of the surface): resolves the eddy-current skin
        depth (20–100 µm at 5–50 kHz in the steel). None (default): no skin refinement.
    skin_growth : float
        Growth rate of the skin refinement (size per distance).
    pole_skin_size : float or None
        Skin size at the pole-piece and magnet surfaces, m, if it should differ from
        ``skin_size`` (refinement studies of one region at a time,
        ``benchmarks/dynamic_mesh_convergence.py``). None (default): ``skin_size``.
    skin_parts : str or None
        Which conducting surfaces the skin grading covers: ``"conducting"`` (beads near a coil,
        pole pieces, magnets; what any ``skin_size`` gives, set automatically) or ``"beads"``
        (the bead surfaces only: the older grading, kept for comparisons). None
        without ``skin_size``.
    """

    flat_fraction: float = 0.4
    wedge_factor: float = 2.0
    near_contacts: int = 4
    far_contact_factor: float = 2.5
    bead_size: float = 0.4e-3
    centre_size: float = 0.1e-3
    part_size: float = 1.2e-3
    far_size: float = 6e-3
    far_growth: float = 0.3
    growth: float = 6.0
    # left out of the mesh cache key at their defaults, so existing keys do not change
    skin_size: float | None = field(default=None, metadata={"omit_if_default": True})
    skin_growth: float = field(default=0.25, metadata={"omit_if_default": True})
    pole_skin_size: float | None = field(default=None, metadata={"omit_if_default": True})
    # None without a skin; "conducting" with one, so every skin mesh's key names its rule and
    # a mesh graded only at the beads (the older rule) is never read for one graded
    # everywhere.
    skin_parts: str | None = field(default=None, metadata={"omit_if_default": True})

    def __post_init__(self) -> None:
        if self.skin_size is not None and self.skin_parts is None:
            object.__setattr__(self, "skin_parts", "conducting")
        for name in ("flat_fraction", "wedge_factor", "far_contact_factor", "bead_size",
                     "centre_size", "part_size", "far_size", "far_growth", "growth"):
            v = getattr(self, name)
            require(v > 0 and math.isfinite(v), f"MeshOptions.{name} must be > 0, got {v}")
        require(self.near_contacts >= 0, "MeshOptions.near_contacts must be >= 0")
        require(self.skin_size is None or (self.skin_size > 0 and math.isfinite(self.skin_size)),
                f"MeshOptions.skin_size must be > 0 or None, got {self.skin_size}")
        require(self.skin_growth > 0, f"MeshOptions.skin_growth must be > 0, got "
                f"{self.skin_growth}")
        require(self.pole_skin_size is None or (self.pole_skin_size > 0
                                                and math.isfinite(self.pole_skin_size)),
                f"MeshOptions.pole_skin_size must be > 0 or None, got {self.pole_skin_size}")
        require(self.skin_parts in ((None,) if self.skin_size is None
                                    else ("conducting", "beads")),
                f"MeshOptions.skin_parts must be 'conducting' or 'beads' with a skin_size "
                f"(None without), got {self.skin_parts!r}")

    def scaled(self, factor: float) -> MeshOptions:
        """All sizes (not the counts) times ``factor`` (refinement studies)."""
        return replace(self, flat_fraction=self.flat_fraction * factor,
                       wedge_factor=self.wedge_factor * factor,
                       bead_size=self.bead_size * factor, centre_size=self.centre_size * factor,
                       part_size=self.part_size * factor, far_size=self.far_size * factor,
                       far_growth=self.far_growth * factor)


#: The OCC model is built in millimetres (OCC's tolerance, 1e-7 model units, would swallow the
#: 0.1 um caps that the contact flats cut off the beads if we worked in metres); gmsh scales the
#: saved mesh back to metres with Mesh.ScalingFactor.
MM = 1e3


def _bead_surface(occ, r: float, zc: float, h: float) -> int:
    """Bead disc (r >= 0 half) truncated to |z - zc| <= h (mm); returns the OCC surface tag."""
    disk = occ.addDisk(0.0, zc, 0.0, r, r)
    box = occ.addRectangle(0.0, zc - h, 0.0, r, 2 * h)
    out, _ = occ.intersect([(2, disk)], [(2, box)])
    internal(len(out) == 1, "internal: bead truncation gave more than one surface")
    return out[0][1]


def _rect_surface(occ, q: Rect) -> int:
    return occ.addRectangle(MM * q.r0, MM * q.z0, 0.0, MM * (q.r1 - q.r0), MM * (q.z1 - q.z0))


def _wedge_field(rim_points: list[int], geometry: SensorGeometry, flat_fraction: float,
                 wedge_factor: float) -> int:
    """Size ~ wedge_factor x air-gap height g + ((a + d)^2 - a^2)/R at distance d from a rim."""
    f = gmsh.model.mesh.field
    b = geometry.beads
    a, big_r, gap = MM * b.flat_radius, MM * b.radius, MM * b.contact_gap
    dist = f.add("Distance")
    f.setNumbers(dist, "PointsList", rim_points)
    s_min = flat_fraction * a
    if gap > 0:  # an air gap between the flats must be resolved across its height
        s_min = min(s_min, wedge_factor * gap)
    wedge = f.add("MathEval")
    # No upper clamp: the size grows quadratically and the other fields take over.
    f.setString(wedge, "F", f"Max({s_min!r}, {wedge_factor!r} * "
                             f"({gap!r} + (2 * {a!r} * F{dist} + F{dist}^2) / {big_r!r}))")
    return wedge


def _box_field(q: Rect, size: float, options: MeshOptions, r_pad: float = 0.0) -> int:
    f = gmsh.model.mesh.field
    bx = f.add("Box")
    f.setNumber(bx, "VIn", size)
    f.setNumber(bx, "VOut", 1e22)
    f.setNumber(bx, "XMin", MM * q.r0)
    f.setNumber(bx, "XMax", MM * q.r1 + r_pad)
    f.setNumber(bx, "YMin", MM * q.z0 - r_pad)
    f.setNumber(bx, "YMax", MM * q.z1 + r_pad)
    f.setNumber(bx, "Thickness", options.growth * MM * options.part_size)
    return bx


#: Top frequency the skin grading is made for, Hz (the highest of
#: :data:`msens.magnetics.dynamic.DEFAULT_FREQUENCIES`).
SKIN_TOP_FREQUENCY = 200e3
#: Relative permeability assumed for the steel in the grading rule (the upper end of the
#: incremental μr at the bias point, 800–1200 in the pole pieces): with σ of 1018 its skin
#: depth at :data:`SKIN_TOP_FREQUENCY` is ~15 µm, below any useful ``skin_size``.
SKIN_STEEL_MU_R = 1000.0


def skin_surface_size(options: MeshOptions, *, sigma: float, mu_r: float,
                      pole: bool = False) -> float:
    """Element size at the surface of a conducting part, m: the ONE grading rule.

    size = max(skin, δ/2), δ = √(2/(ωμ0μrσ)) at :data:`SKIN_TOP_FREQUENCY`, with skin =
    ``options.skin_size`` (``pole_skin_size`` for pole pieces and magnets if given). For the
    steel (σ ≈ 6 MS/m, μr ~ 1000) δ/2 ≈ 7 µm, so the skin size governs; a sintered NdFeB
    magnet (σ ≈ 0.67 MS/m, μr ≈ 1.05) has δ ≈ 1.3 mm at 200 kHz and is graded to ~0.7 mm,
    not to tens of µm it does not need.

    Parameters
    ----------
    options : MeshOptions
        With a ``skin_size``.
    sigma : float
        Conductivity, S/m.
    mu_r : float
        Relative permeability.
    pole : bool
        A pole piece or magnet (``pole_skin_size`` applies) rather than a bead.
    """
    internal(options.skin_size is not None, "internal: skin_surface_size without skin_size")
    skin = options.skin_size
    if pole and options.pole_skin_size is not None:
        skin = options.pole_skin_size
    if sigma <= 0:
        return math.inf
    delta = math.sqrt(2.0 / (2 * math.pi * SKIN_TOP_FREQUENCY * 4e-7 * math.pi * mu_r * sigma))
    return max(skin, 0.5 * delta)


def _min_expr(terms: list[str]) -> str:
    expr = terms[-1]
    for t in reversed(terms[:-1]):  # gmsh's MathEval Min takes two arguments
        expr = f"Min({t}, {expr})"
    return expr


def _rect_distance(q: Rect) -> str:
    """MathEval expression (mm) of the exact distance from (x, y) to the boundary of ``q``
    (inside and out: |signed distance| of a box)."""
    ax = f"Max({MM * q.r0!r} - x, x - {MM * q.r1!r})"
    ay = f"Max({MM * q.z0!r} - y, y - {MM * q.z1!r})"
    return (f"Abs(Sqrt(Max({ax}, 0)^2 + Max({ay}, 0)^2) + Min(Max({ax}, {ay}), 0))")


def skin_beads(geometry: SensorGeometry, options: MeshOptions) -> list[int]:
    """Particles whose bead surfaces the skin grading refines: those within
    ``max(near_contacts, 1)`` of a coil."""
    sensors = [u.coil.particle for u in geometry.sensors]
    return [p for p in geometry.beads.particles
            if min(abs(p - q) for q in sensors) <= max(options.near_contacts, 1)]


def skin_part_sizes(geometry: SensorGeometry, options: MeshOptions) -> list[tuple[Rect, float]]:
    """Pole pieces and magnets the skin grading refines, with their surface sizes, m
    (none with ``skin_parts="beads"``). A magnet is graded as if of the most conductive
    grade msens knows (its grade is a material, not part of the mesh key)."""
    from msens.params.materials import MAGNET_CONDUCTIVITY, SIGMA_1018

    if options.skin_parts != "conducting":
        return []
    sigma_magnet = max(MAGNET_CONDUCTIVITY.values())
    out = []
    for unit in geometry.iter_units():
        for q in geometry.magnet_rects(unit):
            if q.name.startswith("pole_"):
                size = skin_surface_size(options, sigma=SIGMA_1018, mu_r=SKIN_STEEL_MU_R,
                                         pole=True)
            else:
                size = skin_surface_size(options, sigma=sigma_magnet,
                                         mu_r=unit.magnet.recoil_permeability, pole=True)
            if math.isfinite(size) and size < options.part_size:
                out.append((q, size))
    return out


def _skin_field(geometry: SensorGeometry, options: MeshOptions) -> list[int]:
    """Size s + skin_growth·d at distance d (exact) from the surface of each conducting part:
    the beads within ``near_contacts`` of a coil (s = skin_size), the pole pieces and the
    magnets (s from :func:`skin_surface_size`)."""
    b = geometry.beads
    big_r = MM * b.radius
    f = gmsh.model.mesh.field
    out = []
    from msens.params.materials import SIGMA_1018

    bead_size = skin_surface_size(options, sigma=SIGMA_1018, mu_r=SKIN_STEEL_MU_R)
    terms = [f"Abs(Sqrt(x^2 + (y - {MM * b.center(p)!r})^2) - {big_r!r})"
             for p in skin_beads(geometry, options)]
    if terms:
        skin = f.add("MathEval")
        f.setString(skin, "F", f"{MM * bead_size!r} + {options.skin_growth!r} * "
                               f"({_min_expr(terms)})")
        out.append(skin)
    for q, size in skin_part_sizes(geometry, options):
        skin = f.add("MathEval")
        f.setString(skin, "F", f"{MM * size!r} + {options.skin_growth!r} * "
                               f"({_rect_distance(q)})")
        out.append(skin)
    return out


def _set_sizes(geometry: SensorGeometry, options: MeshOptions, part_rects: list[Rect]) -> None:
    """Size fields: contact wedges, bead centres, beads, parts, graded far air (by Min)."""
    f = gmsh.model.mesh.field
    b = geometry.beads
    fields: list[int] = []
    sensors = [u.coil.particle for u in geometry.sensors]
    near, far = [], []
    for upper, _ in b.contacts:
        z = MM * b.contact_z(upper)
        tag = gmsh.model.occ.addPoint(MM * b.flat_radius, z, 0.0)
        d = min(min(abs(upper - p), abs(upper + 1 - p)) for p in sensors)
        (near if d < options.near_contacts else far).append(tag)
    centres = [gmsh.model.occ.addPoint(0.0, MM * b.center(p), 0.0) for p in b.particles]
    gmsh.model.occ.synchronize()
    if near:
        fields.append(_wedge_field(near, geometry, options.flat_fraction, options.wedge_factor))
    if far:
        k = options.far_contact_factor
        fields.append(_wedge_field(far, geometry, k * options.flat_fraction,
                                   k * options.wedge_factor))
    dist = f.add("Distance")
    f.setNumbers(dist, "PointsList", centres)
    centre = f.add("MathEval")  # centre_size within R/10, then growing (no upper clamp)
    f.setString(centre, "F", f"Max({MM * options.centre_size!r}, "
                             f"F{dist} - {0.1 * MM * b.radius!r})")
    fields.append(centre)

    if options.skin_size is not None:
        fields.extend(_skin_field(geometry, options))

    z0, z1 = b.z_span
    fields.append(_box_field(Rect("beads", 0.0, b.radius, z0, z1), MM * options.bead_size,
                             options, r_pad=0.05 * MM * b.radius))
    fields.extend(_box_field(q, MM * options.part_size, options) for q in part_rects)

    # far air: far_size next to the parts, growing with the distance from their bounding box
    rects = geometry.rectangles()
    r1 = MM * max(q.r1 for q in rects)
    zlo, zhi = geometry.parts_z_span()
    zlo, zhi = MM * zlo, MM * zhi
    far_air = f.add("MathEval")
    f.setString(far_air, "F",
                f"Max({MM * options.far_size!r}, {options.far_growth!r} * "
                f"Sqrt(Max(x - {r1!r}, 0)^2 + Max(Max({zlo!r} - y, y - {zhi!r}), 0)^2))")
    fields.append(far_air)

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
    _log.info("meshing the sensor geometry with gmsh (%d beads, %d coil(s); not cached yet)",
              len(b.particles), len(list(geometry.iter_units())))
    from msens.progress import stopwatch

    elapsed = stopwatch()
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
        layer = b.layer_rect()
        if layer is not None:
            named.append((layer.name, _rect_surface(occ, layer)))
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
        internal(bool(air), "internal: no air left after fragmenting the model")

        for name, tags in part_children.items():
            internal(bool(tags), f"internal: part {name} vanished in fragmenting")
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
                if b.contact_layer is not None and upper == b.contact_layer[0]:
                    continue
                z = MM * b.contact_z(upper)
                flat = [t for _, t in gmsh.model.getEntitiesInBoundingBox(
                    -eps, z - eps, -1, a + eps, z + eps, 1, dim=1)]
                internal(len(flat) == 1, f"internal: contact {upper}-{lower} flat not found")
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
    _log.info("meshed in %.1f s", elapsed())
    return path
