"""The parts of a magnetostrictive sensor around the chain: tube, wire, coil, bias magnet.

Dimensions in metres, positions relative to the particle a part is centred on (see
:mod:`msens.field.geometry` for the coordinates and the whole sensor geometry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from msens.errors import require
from msens.params.materials import MAGNET_GRADES


@dataclass(frozen=True)
class Wire:
    """Round enamelled magnet wire.

    Attributes
    ----------
    name : str
    bare_diameter : float
        Copper diameter, m.
    insulated_diameter : float
        Outer diameter over the insulation, m.
    """

    name: str
    bare_diameter: float
    insulated_diameter: float

    def __post_init__(self) -> None:
        require(0 < self.bare_diameter < self.insulated_diameter,
                f"wire {self.name!r}: need 0 < bare_diameter < insulated_diameter, got "
                f"{self.bare_diameter} and {self.insulated_diameter} m")


#: AWG 36: bare copper 0.127 mm (ASTM B258, 0.0050 in). Heavy-build (double) film insulation:
#: overall diameter 0.0060 in max / ~0.152 mm (NEMA MW 1000, heavy build AWG 36).
WIRES: dict[str, Wire] = {
    "AWG36": Wire("AWG36", 0.127e-3, 0.152e-3),
    "AWG34": Wire("AWG34", 0.160e-3, 0.191e-3),
    "AWG38": Wire("AWG38", 0.101e-3, 0.124e-3),
}

#: Packing factor of a layered (square-packed) winding: fraction pi/4 of the winding
#: cross-section filled by insulated round wire. Orthocyclic windings reach pi/(2 sqrt 3) =
#: 0.907 and wild (random) windings are lower, about 0.7-0.8 (Hagedorn, Sell-Le Blanc &
#: Fleischer, *Handbook of Coil Winding*, Springer 2018, ch. 2). pi/4 is a documented guess.
SQUARE_PACKING = math.pi / 4


@dataclass(frozen=True)
class Tube:
    """Plastic tube holding the chain (non-magnetic).

    Attributes
    ----------
    inner_radius, outer_radius : float
        m; paper §2: inner diameter 4.8 mm, outer diameter 12.7 mm.
    """

    inner_radius: float = 2.4e-3
    outer_radius: float = 6.35e-3

    def __post_init__(self) -> None:
        require(0 < self.inner_radius < self.outer_radius,
                f"tube needs 0 < inner_radius < outer_radius, got {self.inner_radius} and "
                f"{self.outer_radius} m")


@dataclass(frozen=True)
class Coil:
    """A pick-up coil wound on a former around the tube, centred on a particle.

    Attributes
    ----------
    particle : int
        The particle at the coil's centre (paper: 13 and 18).
    turns : int
        Number of turns N (paper: 1100).
    length : float
        Winding length, m (paper: 7 mm).
    inner_radius : float
        Winding inner radius, m: former inner radius 6.35 mm + wall 1.6 mm = 7.95 mm.
    wire : Wire
    packing_factor : float
        Fraction of the winding cross-section filled by insulated wire circles (see
        :data:`SQUARE_PACKING`).
    axial_offset : float
        Shift of the coil centre from the particle centre, m (+ = up).
    """

    particle: int = 13
    turns: int = 1100
    length: float = 7e-3
    inner_radius: float = 7.95e-3
    wire: Wire = WIRES["AWG36"]
    packing_factor: float = SQUARE_PACKING
    axial_offset: float = 0.0

    def __post_init__(self) -> None:
        require(isinstance(self.turns, int) and self.turns > 0,
                f"coil at particle {self.particle}: turns must be a positive integer, got "
                f"{self.turns!r}")
        require(self.length > 0, f"coil length must be > 0 m, got {self.length}")
        require(self.inner_radius > 0, f"coil inner_radius must be > 0 m, got "
                f"{self.inner_radius}")
        require(0 < self.packing_factor <= math.pi / (2 * math.sqrt(3)) + 1e-12,
                f"coil packing_factor must be in (0, 0.907] (hexagonal limit), got "
                f"{self.packing_factor}")
        require(self.length >= self.wire.insulated_diameter,
                "coil length must hold at least one turn")

    @property
    def thickness(self) -> float:
        """Radial winding depth, m: N (pi d^2/4) / (packing L)."""
        d = self.wire.insulated_diameter
        return self.turns * math.pi * d**2 / 4 / (self.packing_factor * self.length)

    @property
    def outer_radius(self) -> float:
        """Winding outer radius, m."""
        return self.inner_radius + self.thickness

    @property
    def mean_turn_length(self) -> float:
        """Mean length of one turn, m."""
        return math.pi * (self.inner_radius + self.outer_radius)

    @property
    def area(self) -> float:
        """Winding cross-section in the (r, z) plane, m^2."""
        return self.thickness * self.length


@dataclass(frozen=True)
class BiasMagnet:
    """Equivalent bias magnet: axial ring magnet between two annular steel pole pieces.

    EQUIVALENT, NOT THE REAL PART: the paper's bridge magnet (McMaster-Carr 5841K12) is not
    documented; this ring + pole-piece assembly reproduces its role (an axial bias field over
    about four contacts). The default is ceramic 8 (Br 0.39 T, mu_rec 1.4, MMPA 0100-00), the
    typical material of such cheap bridge/horseshoe magnets (an assumption).

    The pole pieces touch the magnet's end faces; their centres are
    ``length/2 + pole_thickness/2`` above and below the magnet centre, which sits at the
    particle's centre plus ``axial_offset``. Defaults: pole centres 19 mm apart (four bead
    diameters, spanning the four contacts around the sensor bead).

    Attributes
    ----------
    particle : int
        Particle at the assembly's nominal centre.
    grade : str
        Name of the magnet grade (for reports).
    remanence : float
        B_r, T; sign = direction along +z.
    recoil_permeability : float
        mu_rec, relative.
    inner_radius, outer_radius, length : float
        Ring magnet, m.
    pole_inner_radius, pole_outer_radius, pole_thickness : float
        Annular 1018-steel pole pieces, m.
    axial_offset : float
        Shift of the assembly centre from the particle centre, m (+ = up).
    """

    particle: int = 13
    # materials, not geometry: the mesh does not depend on them (the transducer key does)
    grade: str = field(default="ceramic8", metadata={"mesh": False})
    remanence: float = field(default=MAGNET_GRADES["ceramic8"].remanence,
                             metadata={"mesh": False})
    recoil_permeability: float = field(
        default=MAGNET_GRADES["ceramic8"].recoil_permeability, metadata={"mesh": False})
    inner_radius: float = 12.5e-3
    outer_radius: float = 20.0e-3
    length: float = 16.0e-3
    pole_inner_radius: float = 6.5e-3
    pole_outer_radius: float = 20.0e-3
    pole_thickness: float = 3.0e-3
    axial_offset: float = 0.0

    def __post_init__(self) -> None:
        where = f"magnet at particle {self.particle}"
        require(0 < self.inner_radius < self.outer_radius,
                f"{where}: need 0 < inner_radius < outer_radius, got {self.inner_radius} and "
                f"{self.outer_radius} m")
        require(self.length > 0, f"{where}: length must be > 0 m, got {self.length}")
        require(0 < self.pole_inner_radius < self.pole_outer_radius,
                f"{where}: need 0 < pole_inner_radius < pole_outer_radius, got "
                f"{self.pole_inner_radius} and {self.pole_outer_radius} m")
        require(self.pole_thickness >= 0, f"{where}: pole_thickness must be >= 0 m")
        require(self.recoil_permeability > 0,
                f"{where}: recoil_permeability must be > 0, got {self.recoil_permeability}")
        require(math.isfinite(self.remanence) and abs(self.remanence) < 2.0,
                f"{where}: remanence must be a finite value below 2 T, got {self.remanence}")


@dataclass(frozen=True)
class SensorUnit:
    """One MsS: a coil and (optionally) its bias magnet."""

    coil: Coil
    magnet: BiasMagnet | None = None

    def __post_init__(self) -> None:
        if self.magnet is not None:
            require(self.magnet.particle == self.coil.particle,
                    f"magnet particle {self.magnet.particle} differs from its coil's "
                    f"particle {self.coil.particle}")


__all__ = ["SQUARE_PACKING", "WIRES", "BiasMagnet", "Coil", "SensorUnit", "Tube", "Wire"]
