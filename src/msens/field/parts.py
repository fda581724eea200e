"""The parts of a magnetostrictive sensor around the chain: tube, wire, coil, bias magnet.

Dimensions in metres, positions relative to the particle a part is centred on (see
:mod:`msens.field.geometry` for the coordinates and the whole sensor geometry). The coil and
its wire are the read-out's (:class:`msens.readout.coil.Coil`, :class:`~msens.readout.coil.Wire`,
:data:`~msens.readout.coil.WIRES`): one coil type for the field model, the circuit and design.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from msens.errors import require
from msens.params.materials import MAGNET_GRADES
from msens.readout.coil import WIRES, Coil, Wire


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


__all__ = ["WIRES", "BiasMagnet", "Coil", "SensorUnit", "Tube", "Wire"]
