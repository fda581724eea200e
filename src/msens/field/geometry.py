"""Axisymmetric geometry of the magnetostrictive sensor (MsS): beads, coils, bias magnets.

Coordinates are (r, z) in metres, r >= 0 the distance from the chain axis and z upwards with
the wall (the chain's base) at z = 0. Particles are numbered as in the paper (Hurley et al.,
§2): 1 is the striker (above the chain, never in the field model), 2..N rest in the tube and
N (30 in the paper) sits on the wall.

Beads are spheres of radius R truncated by a flat of radius ``a`` at every contact: the flat is
the Hertz contact circle, so neighbour centres are ``2 sqrt(R^2 - a^2)`` apart and neighbours
share the flat as an interface (they touch; no air gap). An optional uniform ``contact_gap``
separates the flats by a thin air layer; it exists for cross-checks (isolated bodies) only.
An optional ``contact_layer`` (one contact) inserts a thin disc between that contact's flats:
a mesh region of its own (``layer_<k>_<k+1>``) that the contact map
(:mod:`msens.magnetics.contact_map`) fills with steel (closed) or air (open) on one mesh.

The plastic tube and the coil former are non-magnetic; they constrain the geometry (validated
here) but are not separate mesh regions (their permeability is that of air).

The bias magnet is an *equivalent*, not the paper's part: the paper's bridge magnet
(McMaster-Carr 5841K12) is undocumented, so it is replaced by an axially magnetised ring magnet
outside the coil between two annular 1018-steel pole pieces that reach in to the tube (design.md
§5). Every dimension is a parameter.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from msens.errors import InputError, require, shorten
from msens.field.parts import (
    BiasMagnet,
    Coil,
    SensorUnit,
    Tube,
)
from msens.mechanics.hertz import hertz_contact_radius, identical_spheres_modulus
from msens.params.materials import BEAD_STEEL, STEEL_1018_BH, BHCurve
from msens.params.paper import BEAD_MASS, BEAD_RADIUS, PAPER_MAGNETIC_FORCE
from msens.params.units import G0

#: Bead diameter of the paper, m (:mod:`msens.params.paper`).
BEAD_DIAMETER = 2 * BEAD_RADIUS


def hertz_flat_radius(load: float, radius: float = BEAD_DIAMETER / 2,
                      youngs_modulus: float = BEAD_STEEL.youngs_modulus,
                      poisson_ratio: float = BEAD_STEEL.poisson_ratio) -> float:
    """Hertz contact radius of two identical spheres pressed together.

    a = (3 F R* / (4 E*))^(1/3), R* = R/2, E* = E / (2 (1 - nu^2)) (Johnson, *Contact
    Mechanics*, 1985, eq. 4.22).

    Parameters
    ----------
    load : float
        Contact force F, N (> 0).
    radius : float
        Sphere radius R, m.
    youngs_modulus, poisson_ratio : float
        E in Pa and nu of both spheres.

    Returns
    -------
    float
        Contact radius a, m.
    """
    require(load > 0, f"contact load must be > 0 N, got {load}")
    e_star = identical_spheres_modulus(youngs_modulus, poisson_ratio)
    return float(hertz_contact_radius(load, radius / 2, e_star))


#: Default contact load for the flat radius, N: the weight of beads 2..13 resting on the upper
#: sensor's middle contact (12 x 0.45 g x g) plus the paper's magnetic estimate of 1.8 N.
DEFAULT_CONTACT_LOAD = 12 * BEAD_MASS * G0 + PAPER_MAGNETIC_FORCE


def _is_int(value: object) -> bool:
    return isinstance(value, int | np.integer) and not isinstance(value, bool)


def _is_real(value: object) -> bool:
    return (isinstance(value, int | float | np.integer | np.floating)
            and not isinstance(value, bool) and math.isfinite(value))


def _require_types(record: object, *, ints: tuple[str, ...] = (),
                   reals: tuple[str, ...] = ()) -> None:
    """InputError naming the first field of ``record`` that is not an integer (``ints``) or a
    finite real number (``reals``): a record built from Python gets the same one message as a
    study key, not a TypeError from a comparison."""
    for names, ok, kind in ((ints, _is_int, "an integer"), (reals, _is_real, "a finite number")):
        for name in names:
            value = getattr(record, name)
            require(ok(value), f"{type(record).__name__}.{name} must be {kind}, got "
                               f"{type(value).__name__} {shorten(value)}")


@dataclass(frozen=True)
class BeadChain:
    """The modelled part of the chain.

    Attributes
    ----------
    first, last : int
        First (top) and last (bottom) particle in the field model, paper numbering,
        2 <= first <= last <= count. Default: the whole chain 2..30; cutting the model five
        beads beyond the sensors (8..23) moves the sensor beads' fields by 2.6 %, seven beads
        by 0.7 % (benchmarks/field_model_convergence.py).
    count : int
        Particle count including the striker (30 in the paper); particle ``count`` rests on
        the wall at z = 0.
    diameter : float
        Bead diameter, m.
    contact_load : float
        Static load used for the Hertz flat radius, N.
    min_flat_radius : float
        Lower bound of the flat radius, m (the flat is max(Hertz(load), this)).
    contact_gap : float
        Air gap between neighbour flats, m; 0 (default) means the beads touch.
    contact_layer : (int, float) or None
        (upper particle k, thickness h in m): a disc of radius ``flat_radius`` and height h
        between the flats of contact k–(k+1); the beads above it sit h higher. None (default):
        no layer (and no change to the mesh key).
    """

    first: int = 2
    last: int = 30
    count: int = 30
    diameter: float = BEAD_DIAMETER
    contact_load: float = DEFAULT_CONTACT_LOAD
    min_flat_radius: float = 0.0
    contact_gap: float = 0.0
    # left out of the mesh key when None, so existing meshes keep their keys
    contact_layer: tuple[int, float] | None = field(default=None,
                                                     metadata={"omit_if_default": True})

    def __post_init__(self) -> None:
        _require_types(self, ints=("first", "last", "count"),
                       reals=("diameter", "contact_load", "min_flat_radius", "contact_gap"))
        if self.contact_layer is not None:
            layer = self.contact_layer
            require(isinstance(layer, tuple | list) and len(layer) == 2
                    and _is_int(layer[0]) and _is_real(layer[1]),
                    "contact_layer must be None or (upper particle: int, thickness in m: "
                    f"float), got {shorten(layer)}")
        require(self.count >= 2, f"chain count must be >= 2 particles, got {self.count}")
        require(2 <= self.first <= self.last <= self.count,
                f"modelled beads must satisfy 2 <= first <= last <= count={self.count}, got "
                f"first={self.first}, last={self.last} (particle 1 is the striker)")
        require(self.diameter > 0, f"bead diameter must be > 0 m, got {self.diameter}")
        require(self.contact_load > 0, f"contact_load must be > 0 N, got {self.contact_load}")
        require(self.min_flat_radius >= 0,
                f"min_flat_radius must be >= 0 m, got {self.min_flat_radius}")
        require(self.contact_gap >= 0, f"contact_gap must be >= 0 m, got {self.contact_gap}")
        require(self.flat_radius < 0.2 * self.radius,
                f"contact flat radius {self.flat_radius:.3g} m must be < 0.2 x bead radius")
        if self.contact_layer is not None:
            k, h = self.contact_layer
            require(self.first <= k < self.last,
                    f"contact_layer: contact {k}-{k + 1} is not between modelled beads "
                    f"{self.first}..{self.last}")
            require(0 < h < 0.1 * self.flat_radius,
                    f"contact_layer thickness must be in (0, {0.1 * self.flat_radius:.3g}) m "
                    f"(a tenth of the flat radius), got {h}")
            require(self.contact_gap == 0, "contact_layer needs contact_gap = 0")

    @property
    def radius(self) -> float:
        """Bead radius R, m."""
        return self.diameter / 2

    @property
    def flat_radius(self) -> float:
        """Contact flat radius a, m."""
        return max(hertz_flat_radius(self.contact_load, self.radius), self.min_flat_radius)

    @property
    def half_height(self) -> float:
        """Half the axial height of a truncated bead, sqrt(R^2 - a^2), m."""
        return math.sqrt(self.radius**2 - self.flat_radius**2)

    @property
    def pitch(self) -> float:
        """Distance between neighbour bead centres, m."""
        return 2 * self.half_height + self.contact_gap

    @property
    def particles(self) -> range:
        """Modelled particle numbers, top to bottom."""
        return range(self.first, self.last + 1)

    def center(self, particle: int) -> float:
        """Axial position of a particle's centre, m (any particle 2..count, modelled or not)."""
        require(2 <= particle <= self.count,
                f"particle {particle} is not in the chain 2..{self.count}")
        z = self.half_height + (self.count - particle) * self.pitch
        if self.contact_layer is not None and particle <= self.contact_layer[0]:
            z += self.contact_layer[1]
        return z

    def contact_z(self, upper: int) -> float:
        """Axial position of the contact plane between ``upper`` and ``upper + 1``, m (the
        mid-plane of a contact layer)."""
        z = self.center(upper) - self.half_height - self.contact_gap / 2
        if self.contact_layer is not None and upper == self.contact_layer[0]:
            z -= self.contact_layer[1] / 2
        return z

    def layer_rect(self) -> Rect | None:
        """The contact layer's disc in the (r, z) plane (None without a layer)."""
        if self.contact_layer is None:
            return None
        k, h = self.contact_layer
        z = self.contact_z(k)
        return Rect(f"layer_{k}_{k + 1}", 0.0, self.flat_radius, z - h / 2, z + h / 2)

    @property
    def contacts(self) -> tuple[tuple[int, int], ...]:
        """Modelled contacts (upper, lower), top to bottom."""
        return tuple((p, p + 1) for p in range(self.first, self.last))

    @property
    def z_span(self) -> tuple[float, float]:
        """(bottom, top) of the modelled beads, m."""
        return (self.center(self.last) - self.half_height,
                self.center(self.first) + self.half_height)


@dataclass(frozen=True)
class AirBox:
    """Truncation of open space: A = 0 on r = radius and on z planes ``margin`` beyond the parts.

    Attributes
    ----------
    radius : float
        Outer radius of the model, m.
    margin : float
        Axial distance from the lowest/highest part to the box's ends, m.

    The defaults (0.32 m, 0.24 m; 16 x the magnet radius) keep the truncation error of the
    sensor beads' fields and contact forces at the level of the remeshing noise (< 0.6 %
    between boxes of half and twice the size); the far air is meshed coarsely (element size
    growing with the distance), so the large box is cheap.
    """

    radius: float = 0.32
    margin: float = 0.24

    def __post_init__(self) -> None:
        require(self.radius > 0 and self.margin > 0,
                f"air box radius and margin must be > 0 m, got {self.radius}, {self.margin}")


@dataclass(frozen=True)
class Rect:
    """Axis-aligned rectangle in the (r, z) half-plane, m."""

    name: str
    r0: float
    r1: float
    z0: float
    z1: float

    def overlaps(self, other: Rect) -> bool:
        """True when the two rectangles share an area (touching edges do not count)."""
        tol = 1e-12
        return (min(self.r1, other.r1) - max(self.r0, other.r0) > tol
                and min(self.z1, other.z1) - max(self.z0, other.z0) > tol)


def same_bh(a: BHCurve, b: BHCurve) -> bool:
    """True when two B–H curves have the same points (names and sources aside)."""
    return a is b or (np.array_equal(a.b, b.b) and np.array_equal(a.h, b.h))


def _default_sensors() -> tuple[SensorUnit, ...]:
    return tuple(SensorUnit(Coil(particle=p), BiasMagnet(particle=p)) for p in (13, 18))


@dataclass(frozen=True)
class SensorGeometry:
    """Complete axisymmetric model: beads, tube, sensors (coil + magnet), air box.

    Validation (raises :class:`msens.errors.InputError`): parts may not overlap, beads must fit
    in the tube, coils and magnets must lie outside the tube, each coil must sit at a modelled
    particle, and the air box must enclose everything.

    Attributes
    ----------
    beads : BeadChain
    tube : Tube
    sensors : tuple of SensorUnit
    air : AirBox
    steel : BHCurve
        Normal magnetisation curve of the beads and pole pieces (default AISI 1018, FEMM
        library). It is a material, not a dimension: the mesh does not depend on it
        (:func:`msens.field.cache.geometry_key` leaves it out).
    reversibility : float
        Small-signal permeability of that steel about the bias point: the fraction c in
        (0, 1] of its differential susceptibility that is reversible
        (:class:`msens.field.regions.NonlinearSoft`); 1 = the differential slope. A material
        property: not in the mesh key.
    """

    beads: BeadChain = field(default_factory=BeadChain)
    tube: Tube = field(default_factory=Tube)
    sensors: tuple[SensorUnit, ...] = field(default_factory=_default_sensors)
    air: AirBox = field(default_factory=AirBox)
    steel: BHCurve = field(default=STEEL_1018_BH, metadata={"mesh": False})
    reversibility: float = field(default=1.0, metadata={"mesh": False})

    def __post_init__(self) -> None:
        require(0.0 < self.reversibility <= 1.0,
                f"reversibility must be in (0, 1], got {self.reversibility!r}")
        b, t = self.beads, self.tube
        require(b.radius <= t.inner_radius,
                f"beads of diameter {b.diameter} m do not fit in the tube of inner radius "
                f"{t.inner_radius} m")
        particles = [s.coil.particle for s in self.sensors]
        require(len(set(particles)) == len(particles),
                f"two sensors at the same particle: {particles}")
        for s in self.sensors:
            c = s.coil
            require(c.particle in b.particles,
                    f"coil at particle {c.particle} is outside the modelled chain "
                    f"{b.first}..{b.last}")
            require(c.inner_radius >= t.outer_radius,
                    f"coil at particle {c.particle}: inner_radius {c.inner_radius} m is inside "
                    f"the tube (outer radius {t.outer_radius} m)")
            m = s.magnet
            if m is not None:
                require(m.inner_radius >= t.outer_radius and m.pole_inner_radius
                        >= t.outer_radius,
                        f"magnet at particle {m.particle} reaches inside the tube (outer radius "
                        f"{t.outer_radius} m): inner_radius {m.inner_radius} m, "
                        f"pole_inner_radius {m.pole_inner_radius} m")
        rects = self.rectangles()
        for i, p in enumerate(rects):
            for q in rects[i + 1:]:
                if p.overlaps(q):
                    raise InputError(f"parts overlap: {p.name} and {q.name} "
                                     f"(r {p.r0:.4g}..{p.r1:.4g} / {q.r0:.4g}..{q.r1:.4g} m, "
                                     f"z {p.z0:.4g}..{p.z1:.4g} / {q.z0:.4g}..{q.z1:.4g} m)")
        r_max = max(q.r1 for q in rects)
        require(self.air.radius > 1.5 * r_max,
                f"air box radius {self.air.radius} m must exceed 1.5 x the largest part "
                f"radius {r_max} m")

    @property
    def default_steel(self) -> bool:
        """True when :attr:`steel` tabulates the same points as the default 1018 curve."""
        return same_bh(self.steel, STEEL_1018_BH)

    def coil_rect(self, unit: SensorUnit) -> Rect:
        """Winding cross-section of a sensor's coil."""
        c = unit.coil
        zc = self.beads.center(c.particle) + c.axial_offset
        return Rect(f"coil_{c.particle}", c.inner_radius, c.outer_radius,
                    zc - c.length / 2, zc + c.length / 2)

    def magnet_rects(self, unit: SensorUnit) -> tuple[Rect, ...]:
        """Ring magnet, lower pole and upper pole of a sensor (empty without magnet)."""
        m = unit.magnet
        if m is None:
            return ()
        zc = self.beads.center(m.particle) + m.axial_offset
        h = m.length / 2
        out = [Rect(f"magnet_{m.particle}", m.inner_radius, m.outer_radius, zc - h, zc + h)]
        if m.pole_thickness > 0:
            out += [Rect(f"pole_{m.particle}_lower", m.pole_inner_radius, m.pole_outer_radius,
                         zc - h - m.pole_thickness, zc - h),
                    Rect(f"pole_{m.particle}_upper", m.pole_inner_radius, m.pole_outer_radius,
                         zc + h, zc + h + m.pole_thickness)]
        return tuple(out)

    def rectangles(self) -> list[Rect]:
        """Bounding rectangles of all parts, the bead column first."""
        z0, z1 = self.beads.z_span
        out = [Rect("beads", 0.0, self.beads.radius, z0, z1)]
        for s in self.sensors:
            out.append(self.coil_rect(s))
            out.extend(self.magnet_rects(s))
        return out

    def parts_z_span(self) -> tuple[float, float]:
        """(bottom, top) of all parts, m."""
        rects = self.rectangles()
        return min(q.z0 for q in rects), max(q.z1 for q in rects)

    def box(self) -> Rect:
        """The truncation box [0, radius] x [bottom - margin, top + margin]."""
        z0, z1 = self.parts_z_span()
        return Rect("air", 0.0, self.air.radius, z0 - self.air.margin, z1 + self.air.margin)

    def iter_units(self) -> Iterator[SensorUnit]:
        """Sensor units in particle order."""
        return iter(sorted(self.sensors, key=lambda s: s.coil.particle))
