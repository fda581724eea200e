"""What fills a subdomain of the axisymmetric field model.

Each region kind is a frozen record with its constitutive law H(B) (and, for windings, the
source current). All are isotropic except the permanent magnet's remanence, which is axial.
"""

from __future__ import annotations

from dataclasses import dataclass

from msens.errors import require
from msens.params.materials import BHCurve


@dataclass(frozen=True)
class Air:
    """Vacuum permeability, no source: H = B/μ0 (also plastic, copper, any non-magnetic part)."""


@dataclass(frozen=True)
class LinearMagnetic:
    """Linear isotropic material: H = B/(μ0 μ_r).

    Attributes
    ----------
    mu_r : float
        Relative permeability, > 0.
    """

    mu_r: float

    def __post_init__(self) -> None:
        require(self.mu_r > 0, f"LinearMagnetic.mu_r must be > 0, got {self.mu_r}")


@dataclass(frozen=True)
class NonlinearSoft:
    """Nonlinear isotropic soft magnetic material: ``H = H(|B|) B/|B|`` from a B–H table.

    Attributes
    ----------
    curve : BHCurve
        Anhysteretic curve, e.g. :data:`msens.params.materials.STEEL_1018_BH`.
    reversibility : float
        Fraction c in (0, 1] of the differential susceptibility that small signals about the
        bias see (the reversible part, Jiles–Atherton's c): along B the small-signal
        permeability is μ0 + c (dB/dH − μ0). 1 = the differential slope of the curve. The
        bias solve does not use it.
    """

    curve: BHCurve
    reversibility: float = 1.0

    def __post_init__(self) -> None:
        require(0.0 < self.reversibility <= 1.0,
                f"reversibility must be in (0, 1], got {self.reversibility!r}")


@dataclass(frozen=True)
class PermanentMagnet:
    """Linear (recoil-line) axially magnetised permanent magnet: B = μ0 μ_rec H + B_r e_z.

    Attributes
    ----------
    remanence : float
        B_r, T; its sign is the magnetisation direction along +z.
    recoil_permeability : float
        μ_rec, relative, > 0 (1 for an ideal rigid magnet).
    """

    remanence: float
    recoil_permeability: float = 1.0

    def __post_init__(self) -> None:
        require(self.recoil_permeability > 0,
                f"PermanentMagnet.recoil_permeability must be > 0, got "
                f"{self.recoil_permeability}")


@dataclass(frozen=True)
class CurrentRegion:
    """Homogenised coil cross-section carrying an azimuthal current density, μ = μ0.

    Attributes
    ----------
    current_density : float
        J_φ = N I / S, A/m², positive along +φ (gives +B_z inside the coil).
    """

    current_density: float


Region = Air | LinearMagnetic | NonlinearSoft | PermanentMagnet | CurrentRegion
