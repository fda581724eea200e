"""Material records with their sources.

All values SI. Each record names where its numbers come from; values that are estimates
rather than measurements say so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ElasticMaterial:
    """Isotropic elastic solid.

    Attributes
    ----------
    name : str
    youngs_modulus : float
        Young's modulus E, Pa.
    poisson_ratio : float
        Poisson's ratio nu, dimensionless.
    density : float
        Mass density, kg/m^3.
    source : str
        Where the numbers come from.
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float
    density: float
    source: str


#: Low-carbon steel beads of the paper (McMaster-Carr 96455K51): 4.76 mm, 0.45 g
#: => rho = 0.45e-3 / (pi/6 * 4.76e-3**3) = 7970 kg/m^3. E = 200 GPa and nu = 0.29 are
#: handbook values for AISI 1018 (ASM Handbook vol. 1); nu is an assumption of design.md §7.
BEAD_STEEL = ElasticMaterial(
    name="low-carbon steel (AISI 1018)",
    youngs_modulus=200e9,
    poisson_ratio=0.29,
    density=7970.0,
    source="paper §2 (mass, diameter); ASM Handbook vol. 1 (E, nu)",
)

#: Piezo rods (Piezo Kinetics ND0.187-0.000-0.236-509): 0.8144 g, 4.76 mm x 6 mm,
#: E = 63 GPa, nu = 0.31 from the manufacturer via the paper §2.
PIEZO_ROD = ElasticMaterial(
    name="PZT rod (Piezo Kinetics ND0.187-0.000-0.236-509)",
    youngs_modulus=63e9,
    poisson_ratio=0.31,
    density=0.8144e-3 / (np.pi / 4 * 4.76e-3**2 * 6e-3),
    source="paper §2 (manufacturer data)",
)

#: Piezo rod mass, kg (paper §2).
PIEZO_ROD_MASS = 0.8144e-3
#: Piezo rod length, m (paper §2).
PIEZO_ROD_LENGTH = 6e-3


@dataclass(frozen=True)
class BHCurve:
    """Anhysteretic (normal) magnetisation curve of a soft magnetic material.

    Attributes
    ----------
    name : str
    b : ndarray, shape (n,)
        Flux density, T, strictly increasing from 0.
    h : ndarray, shape (n,)
        Field strength, A/m, strictly increasing from 0.
    source : str
    """

    name: str
    b: np.ndarray
    h: np.ndarray
    source: str


#: AISI 1018 steel, B-H points from the FEMM material library ("1018 Steel").
STEEL_1018_BH = BHCurve(
    name="1018 steel",
    b=np.array([0.0, 0.2503, 0.925, 1.25, 1.39, 1.525, 1.71, 1.87, 1.955, 2.02, 2.11,
                2.225, 2.43]),
    h=np.array([0.0, 238.7, 795.8, 1591.6, 2387.3, 3978.9, 7957.8, 15915.5, 23873.0,
                39789.0, 79577.0, 159155.0, 318310.0]),
    source="FEMM 4.2 material library, '1018 Steel'",
)

#: Reversible fraction c of a steel's differential susceptibility, for small signals about a
#: bias point (the reversibility coefficient of the Jiles–Atherton model). 0.1 is the value
#: usually quoted for steels (D. C. Jiles, D. L. Atherton, J. Magn. Magn. Mater. 61, 48-60
#: (1986); design.md §7): an estimate, not a measurement of 1018. With the 1018 curve it gives
#: a small-signal relative permeability of about 80-100 in the bead bulk (differential: 800-1000).
STEEL_REVERSIBILITY = 0.1


@dataclass(frozen=True)
class MagnetGrade:
    """Linear permanent-magnet model B = mu0 mu_rec H + B_r (recoil line).

    Attributes
    ----------
    name : str
    remanence : float
        B_r, T.
    recoil_permeability : float
        mu_rec, relative, dimensionless.
    source : str
    """

    name: str
    remanence: float
    recoil_permeability: float
    source: str


MAGNET_GRADES: dict[str, MagnetGrade] = {
    "ceramic8": MagnetGrade("ceramic 8 (hard ferrite)", 0.39, 1.4,
                            "MMPA Standard 0100-00, grade C8 (typical values)"),
    "N38": MagnetGrade("NdFeB N38", 1.24, 1.05,
                       "typical sintered NdFeB N38 datasheet: Br 1.22-1.26 T, mu_rec 1.05"),
    "N42": MagnetGrade("NdFeB N42", 1.30, 1.05,
                       "typical sintered NdFeB N42 datasheet: Br 1.28-1.32 T, mu_rec 1.05"),
}


#: Electrical conductivity of the beads' 1018 steel, S/m. ASSUMPTION (no measurement of the
#: beads): annealed AISI 1018 has a resistivity of 15.9 µΩ cm at 0 °C and 21.9 µΩ cm at 100 °C
#: (MatWeb/ASM data sheet for AISI 1018, "Electrical Resistivity"), i.e. 6.3 MS/m at 0 °C and
#: ~5.85 MS/m at 20 °C by linear interpolation; 6.0 MS/m is the round value of design.md §5.
SIGMA_1018 = 6.0e6

#: Electrical conductivity of the magnet grades of :data:`MAGNET_GRADES`, S/m.
#: ceramic8: hard ferrite is an oxide ceramic, an insulator for eddy-current purposes
#: (ASSUMPTION: resistivity of order 1e4 Ω m on typical ferrite data sheets — not measured;
#: any value below ~1 S/m gives no screening at 200 kHz in a 7 mm wall). NdFeB: resistivity
#: 150 µΩ cm, σ = 0.667 MS/m (Stanford Magnets, "Characteristics of NdFeB magnets", physical
#: properties table; 120–160 µΩ cm elsewhere).
MAGNET_CONDUCTIVITY: dict[str, float] = {"ceramic8": 0.0, "N38": 0.667e6, "N42": 0.667e6}
