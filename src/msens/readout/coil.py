"""The pick-up coil: one type (:class:`Coil`) for the field model, the circuit and design.

A multilayer coil of round magnet wire on a former around the tube, centred on a particle:
its wire (:class:`Wire`, :data:`WIRES`, :func:`wire_for`), its geometry from turns, length,
inner radius and packing; copper resistance; Wheeler's air-core inductance (a quick check,
the field model gives the real L); and an estimate of the winding's self-capacitance. The
field model meshes the same :class:`Coil` (:mod:`msens.field.parts` uses it).

Packing convention: ``packing_factor`` is the fraction of the winding's (r, z) cross-section
that the insulated wire circles fill: π/4 ≈ 0.785 for a layer-on-layer (square) winding,
π/(2√3) ≈ 0.907 for a perfect orthocyclic one; wild (random) windings reach about 0.7–0.8
(Hagedorn, Sell-Le Blanc & Fleischer, *Handbook of Coil Winding*, Springer 2018, ch. 2). The
default is the square value π/4, a documented guess: the paper does not say how its coil was
wound, and π/4 lies inside the range of a wild winding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from msens.errors import InputError, require
from msens.params.units import ALPHA_COPPER, MU0, RHO_COPPER

#: Vacuum permittivity, F/m (CODATA 2018), from ε0 = 1/(μ0 c²).
EPS0 = 1.0 / (MU0 * 299_792_458.0**2)

#: Fill fractions of insulated round wire in the winding cross-section (see module notes).
PACKING: dict[str, float] = {
    "square": math.pi / 4.0,
    "orthocyclic": math.pi / (2.0 * math.sqrt(3.0)),
}
DEFAULT_PACKING = "square"

#: Relative permittivity of the wire enamel (polyurethane / polyester-imide film, 3–4 in
#: manufacturers' data). 3.5 is an assumption, used only by the self-capacitance estimate.
ENAMEL_PERMITTIVITY = 3.5

#: Heavy-build (double film) maximum overall diameter, inches, by AWG, per NEMA MW 1000 as
#: tabulated by magnet-wire makers (e.g. MWS Wire Industries Techbook). AWG 36: 0.0060 in =
#: 0.152 mm; 34 and 38 agree with msens.field.geometry. The other sizes are transcribed
#: from such tables, not re-checked against the standard here.
_HEAVY_BUILD_OD_IN: dict[int, float] = {
    30: 0.0114, 32: 0.0093, 34: 0.0075, 36: 0.0060, 38: 0.0049, 40: 0.0039,
}


def awg_diameter(gauge: int) -> float:
    """Bare copper diameter of American Wire Gauge ``gauge``, m.

    d = 0.127 mm · 92^((36 − n)/39), the defining formula of ASTM B258 (AWG 36 = 0.005 in).

    Parameters
    ----------
    gauge : int
        AWG number, 0 to 56 (0000 is not supported).
    """
    require(isinstance(gauge, int | np.integer) and 0 <= gauge <= 56,
            f"wire gauge must be an integer AWG number 0..56, got {gauge!r}")
    return 0.127e-3 * 92.0 ** ((36 - int(gauge)) / 39.0)


def heavy_build_diameter(gauge: int) -> float:
    """Maximum overall diameter of heavy-build magnet wire of AWG ``gauge``, m.

    Raises :class:`InputError` for gauges not in the table (30–40 even); pass the insulated
    diameter explicitly to :func:`coil_from` (or :func:`wire_for`) for those.
    """
    require(gauge in _HEAVY_BUILD_OD_IN,
            f"no heavy-build diameter tabulated for AWG {gauge}; tabulated: "
            f"{sorted(_HEAVY_BUILD_OD_IN)} (or give insulated_diameter explicitly)")
    return _HEAVY_BUILD_OD_IN[gauge] * 25.4e-3


def _parse_wire(wire: str | int) -> int:
    """AWG number from ``"AWG36"``, ``"36"`` or ``36``."""
    if isinstance(wire, int | np.integer):
        return int(wire)
    text = str(wire).strip().upper().removeprefix("AWG").strip()
    if not text.isdigit():
        raise InputError(f"coil wire must look like 'AWG36' or be an AWG number, got {wire!r}")
    return int(text)


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


#: The wires the field model's committed artifacts were made with. AWG 36: bare copper
#: 0.127 mm (ASTM B258, 0.0050 in); heavy-build (double) film insulation: overall diameter
#: 0.0060 in max / ~0.152 mm (NEMA MW 1000, heavy build AWG 36). Other gauges:
#: :func:`wire_for` (ASTM B258 bare, :func:`heavy_build_diameter` insulated).
WIRES: dict[str, Wire] = {
    "AWG36": Wire("AWG36", 0.127e-3, 0.152e-3),
    "AWG34": Wire("AWG34", 0.160e-3, 0.191e-3),
    "AWG38": Wire("AWG38", 0.101e-3, 0.124e-3),
}


def wire_for(wire: str | int, insulated_diameter: float | None = None) -> Wire:
    """The wire of an AWG name or number (``"AWG36"``, ``36``): :data:`WIRES` where it has
    the gauge, else the ASTM B258 bare diameter (:func:`awg_diameter`) with the heavy-build
    insulation (:func:`heavy_build_diameter`) or ``insulated_diameter`` (m) if given."""
    gauge = _parse_wire(wire)
    name = f"AWG{gauge}"
    if insulated_diameter is None and name in WIRES:
        return WIRES[name]
    d_ins = heavy_build_diameter(gauge) if insulated_diameter is None else insulated_diameter
    return Wire(name, awg_diameter(gauge), float(d_ins))


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
        Winding length along the axis, m (paper: 7 mm).
    inner_radius : float
        Winding inner radius, m: former inner radius 6.35 mm + wall 1.6 mm = 7.95 mm.
    wire : Wire
    packing_factor : float
        Fraction of the winding cross-section filled by insulated wire circles (module
        notes; default square, π/4).
    axial_offset : float
        Shift of the coil centre from the particle centre, m (+ = up).
    """

    particle: int = 13
    turns: int = 1100
    length: float = 7e-3
    inner_radius: float = 7.95e-3
    wire: Wire = WIRES["AWG36"]
    packing_factor: float = PACKING[DEFAULT_PACKING]
    axial_offset: float = 0.0

    def __post_init__(self) -> None:
        require(isinstance(self.turns, int) and self.turns > 0,
                f"coil at particle {self.particle}: turns must be a positive integer, got "
                f"{self.turns!r}")
        require(self.length > 0, f"coil length must be > 0 m, got {self.length}")
        require(self.inner_radius > 0, f"coil inner_radius must be > 0 m, got "
                f"{self.inner_radius}")
        require(0 < self.packing_factor <= PACKING["orthocyclic"] + 1e-12,
                f"coil packing_factor must be in (0, 0.907] (hexagonal limit), got "
                f"{self.packing_factor}")
        require(self.length >= self.wire.insulated_diameter,
                "coil length must hold at least one turn")

    @property
    def thickness(self) -> float:
        """Radial winding depth (build), m: N (π d_ins²/4) / (packing · length)."""
        d = self.wire.insulated_diameter
        return self.turns * math.pi * d**2 / 4 / (self.packing_factor * self.length)

    @property
    def outer_radius(self) -> float:
        """Winding outer radius, m."""
        return self.inner_radius + self.thickness

    @property
    def mean_radius(self) -> float:
        """Mean turn radius (r_in + r_out)/2, m."""
        return self.inner_radius + 0.5 * self.thickness

    @property
    def mean_turn_length(self) -> float:
        """Mean length of one turn, π (r_in + r_out), m."""
        return math.pi * (self.inner_radius + self.outer_radius)

    @property
    def area(self) -> float:
        """Winding cross-section in the (r, z) plane, m^2."""
        return self.thickness * self.length

    @property
    def wire_length(self) -> float:
        """Total wire length in the winding (leads excluded), m."""
        return self.turns * self.mean_turn_length

    @property
    def turns_per_layer(self) -> int:
        """Turns side by side in one layer, floor(length / d_ins)."""
        return max(1, math.floor(self.length / self.wire.insulated_diameter * (1 + 1e-12)))

    @property
    def layers(self) -> int:
        """Number of layers, ceil(N / turns_per_layer)."""
        return -(-int(self.turns) // self.turns_per_layer)

    @property
    def copper_area(self) -> float:
        """Copper cross-section of the wire, m²."""
        return math.pi * self.wire.bare_diameter**2 / 4.0

    def resistance(self, temperature_K: float = 293.15) -> float:
        """DC copper resistance of the winding, Ω.

        R = ρ₂₀ (1 + α (T − 293.15 K)) · N · π (r_in + r_out) / (π d²/4), with ρ₂₀ and α of
        annealed copper (IEC 60028, :mod:`msens.params.units`). Leads are not included.

        Parameters
        ----------
        temperature_K : float
            Winding temperature, K.
        """
        require(temperature_K > 0, f"temperature must be > 0 K, got {temperature_K}")
        rho = RHO_COPPER * (1.0 + ALPHA_COPPER * (temperature_K - 293.15))
        return rho * self.wire_length / self.copper_area


def coil_from(turns: int, length: float, inner_radius: float, wire: str | int = "AWG36",
              packing: str | float = DEFAULT_PACKING, *,
              insulated_diameter: float | None = None, particle: int = 13) -> Coil:
    """A :class:`Coil` from a coil description by wire gauge and packing name.

    Parameters
    ----------
    turns : int
    length : float
        Winding length, m.
    inner_radius : float
        Winding inner radius, m (paper: 12.7 mm former + 1.6 mm wall → 7.95 mm).
    wire : str or int
        ``"AWG36"`` or an AWG number (:func:`wire_for`).
    packing : str or float
        ``"square"`` (default, π/4), ``"orthocyclic"`` (π/(2√3)) or a fill fraction.
    insulated_diameter : float, optional
        Overall wire diameter, m; default that of :func:`wire_for`.
    particle : int
        The particle the coil is centred on.

    Returns
    -------
    Coil
    """
    w = wire_for(wire, insulated_diameter)
    if isinstance(packing, str):
        require(packing in PACKING,
                f"coil packing must be one of {sorted(PACKING)} or a number, got {packing!r}")
        fill = PACKING[packing]
    else:
        fill = float(packing)
    return Coil(particle=particle, turns=int(turns), length=float(length),
                inner_radius=float(inner_radius), wire=w, packing_factor=fill)


def wheeler_inductance(coil: Coil) -> float:
    """Air-core inductance by Wheeler's multilayer formula, H.

    L[μH] = 0.8 a² N² / (6a + 9b + 10c) with a the mean radius, b the length and c the
    radial depth, all in inches (H. A. Wheeler, "Simple inductance formulas for radio
    coils", Proc. IRE 16(10):1398–1400, 1928; about 1 % when the three denominator terms are
    of similar size). In SI: L = 0.8e-6 / 0.0254 · a² N² / (6a + 9b + 10c), lengths in m.
    A quick check only: the field model's incremental solve gives the real L.
    """
    a = coil.mean_radius
    b = coil.length
    c = coil.thickness
    return 0.8e-6 / 0.0254 * a**2 * coil.turns**2 / (6.0 * a + 9.0 * b + 10.0 * c)


def turn_to_turn_capacitance(turn_length: float, bare_diameter: float,
                             insulated_diameter: float,
                             permittivity: float = ENAMEL_PERMITTIVITY) -> float:
    """Capacitance between two touching enamelled turns, F.

    Massarini & Kazimierczuk, "Self-capacitance of inductors", IEEE Trans. Power Electron.
    12(4):671–676, 1997, eq. for C_tt: with θ* = arccos(1 − ln(D_o/D_c)/ε_r),
    C_tt = ε0 l_t [ε_r θ*/ln(D_o/D_c) + cot(θ*/2) − cot(π/12)]
    (film plus the air wedge between the wires, field lines taken as arcs up to ±π/6).

    Parameters
    ----------
    turn_length : float
        Length of the turn l_t, m.
    bare_diameter, insulated_diameter : float
        D_c and D_o, m.
    permittivity : float
        Relative permittivity of the enamel.
    """
    require(0 < bare_diameter < insulated_diameter, "need 0 < bare < insulated diameter")
    require(permittivity >= 1.0, f"enamel permittivity must be >= 1, got {permittivity}")
    log_ratio = math.log(insulated_diameter / bare_diameter)
    cos_theta = 1.0 - log_ratio / permittivity
    require(cos_theta > math.cos(math.pi / 6),
            "enamel too thick for the Massarini–Kazimierczuk cell (θ* must be < π/6)")
    theta = math.acos(cos_theta)
    per_length = (permittivity * theta / log_ratio + 1.0 / math.tan(theta / 2.0)
                  - 1.0 / math.tan(math.pi / 12.0))
    return EPS0 * turn_length * per_length


def winding_capacitance(coil: Coil, permittivity: float = ENAMEL_PERMITTIVITY) -> float:
    """ESTIMATE of the winding's self-capacitance (terminal to terminal), F.

    Multilayer (layers ≥ 2), wound back and forth layer by layer: the voltage between
    adjacent layers i, i+1 grows linearly from 0 to 2V/n_l along the winding, so the stored
    energy gives C = (4 / (3 n_l²)) Σ_i C_ll,i (the energy method of Massarini &
    Kazimierczuk 1997 as applied to layers by Dalessandro, Cavalcante & Kolar, IEEE Trans.
    Power Electron. 22(5):2081–2092, 2007). C_ll,i = turns_per_layer · C_tt at the
    interface radius: each turn faces one turn of the next layer (square cell), C_tt from
    :func:`turn_to_turn_capacitance`. Single layer: 1.366 C_tt (Massarini & Kazimierczuk).
    Ignores the former, the leads and the real (wild) wire positions, so treat the value as
    an order-of-magnitude estimate (±50 %).
    """
    n_l = coil.layers
    bare, insulated = coil.wire.bare_diameter, coil.wire.insulated_diameter
    if n_l == 1:
        c_tt = turn_to_turn_capacitance(coil.mean_turn_length, bare, insulated, permittivity)
        return 1.366 * c_tt
    pitch = coil.thickness / n_l
    radii = coil.inner_radius + pitch * np.arange(1, n_l)
    c_ll = sum(coil.turns_per_layer
               * turn_to_turn_capacitance(2.0 * math.pi * r, bare, insulated, permittivity)
               for r in radii)
    return float(4.0 / (3.0 * n_l**2) * c_ll)
