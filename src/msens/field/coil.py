"""Winding geometry and resistance of a multilayer coil of round magnet wire."""

from __future__ import annotations

import math
from dataclasses import dataclass

from msens.errors import require
from msens.units import ALPHA_COPPER, RHO_COPPER


@dataclass(frozen=True)
class Wire:
    """Round enamelled magnet wire.

    Attributes
    ----------
    name : str
    bare_diameter : float
        Copper diameter, m.
    insulated_diameter : float
        Overall diameter with the enamel, m.
    source : str
    """

    name: str
    bare_diameter: float
    insulated_diameter: float
    source: str


def awg_diameter(gauge: int) -> float:
    """Bare diameter of American Wire Gauge ``gauge``, m: d = 0.127 mm · 92^((36 − n)/39).

    This is the defining formula of ASTM B258 (AWG 36 = 0.005 in = 0.127 mm exactly).
    """
    return 0.127e-3 * 92.0 ** ((36 - gauge) / 39.0)


#: AWG 36 magnet wire: bare 0.127 mm (ASTM B258); heavy-build (double) enamel maximum
#: overall diameter 0.0060 in = 0.152 mm (NEMA MW 1000, heavy build, 36 AWG).
AWG36 = Wire("AWG36", awg_diameter(36), 0.152e-3,
             "ASTM B258 (bare); NEMA MW 1000 heavy build max. OD (insulated)")

WIRES: dict[str, Wire] = {"AWG36": AWG36}


def winding_outer_radius(turns: int, length: float, inner_radius: float,
                         insulated_diameter: float, packing: float = 1.0) -> float:
    """Outer radius of a winding that fills its cross-section with ``turns`` wires.

    Each turn occupies d²/``packing`` of the winding cross-section: ``packing`` = 1 for a
    layer (square) winding, 2/√3 ≈ 1.155 for perfect orthocyclic (hexagonal) packing, < 1
    for a loose random winding. Build = N d² / (packing · length).

    Parameters
    ----------
    turns : int
    length : float
        Winding length along the axis, m.
    inner_radius : float
        m.
    insulated_diameter : float
        m.
    packing : float
        Dimensionless, see above.

    Returns
    -------
    float
        Outer radius, m.
    """
    require(turns > 0, f"coil turns must be > 0, got {turns}")
    require(length > 0 and inner_radius >= 0 and insulated_diameter > 0 and packing > 0,
            "coil length, wire diameter and packing must be > 0 and inner radius >= 0")
    return inner_radius + turns * insulated_diameter**2 / (packing * length)


def coil_resistance(turns: int, inner_radius: float, outer_radius: float,
                    wire_diameter: float, *, resistivity: float = RHO_COPPER,
                    temperature: float = 20.0) -> float:
    """DC resistance of the winding, Ω: ρ(T) · N · 2π r_mean / (π d²/4).

    Parameters
    ----------
    turns : int
    inner_radius, outer_radius : float
        Winding radii, m (mean turn radius is their average).
    wire_diameter : float
        Bare copper diameter, m.
    resistivity : float
        Ω m at 20 °C (default annealed copper, IEC 60028).
    temperature : float
        °C; copper's coefficient ALPHA_COPPER (IEC 60028) scales ρ.
    """
    require(turns > 0, f"coil turns must be > 0, got {turns}")
    require(0 <= inner_radius < outer_radius, "coil radii must satisfy 0 <= inner < outer")
    require(wire_diameter > 0, f"wire diameter must be > 0, got {wire_diameter}")
    rho = resistivity * (1.0 + ALPHA_COPPER * (temperature - 20.0))
    length = turns * math.pi * (inner_radius + outer_radius)
    return rho * length / (math.pi * wire_diameter**2 / 4.0)
