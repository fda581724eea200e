"""The study schema (``msens.study/1``): frozen dataclasses of validated study values.

Every later stage receives these typed, checked records; they are built only by the readers
(:mod:`msens.config.study` and the ``read_*`` modules of this package). Units are SI
throughout and appear in the field names.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from msens.chain.model import DampingLaw as Damping
from msens.chain.published import N_PARTICLES
from msens.params.materials import (
    BEAD_STEEL,
    PIEZO_ROD,
    PIEZO_ROD_LENGTH,
    PIEZO_ROD_MASS,
    BHCurve,
)
from msens.params.paper import BEAD_MASS, BEAD_RADIUS
from msens.params.units import G0
from msens.readout.sensors import SensorKind

SCHEMA = "msens.study/1"

#: The main job: the paper's MsS predicted from physics.
DEFAULT_STUDY = "paper-mss"

#: The paper's three sensing setups (Table 2); the default study of ``msens diagnose``.
PAPER_TABLE2 = "paper-table2"


class MssModel(enum.Enum):
    """How a magnetostrictive sensor's signal is modelled."""

    FOUR_CONTACT = "four-contact"  # the paper's hypothesis: mean of four contact forces
    PHYSICS = "physics"  # field model + Villari law + reciprocity


@dataclass(frozen=True)
class WallSpec:
    """The half-space the chain stands on. Moduli in Pa."""

    youngs_modulus_pa: float = 200e9
    poisson_ratio: float = 0.29


@dataclass(frozen=True)
class ChainSpec:
    """The bead chain below the striker.

    Attributes
    ----------
    beads : int
        Number of beads below the striker (the paper: 29); particles are numbered
        1 (striker) to ``beads + 1`` (on the wall).
    bead_diameter_m, bead_mass_kg : float
        Bead diameter (m) and mass (kg); the striker is an identical bead.
    youngs_modulus_pa, poisson_ratio : float
        Bead elastic constants.
    gravity_m_per_s2 : float
        Acceleration of gravity along the chain, toward the wall.
    damping : Damping
        Dissipation law in the contacts.
    gamma_contact, gamma_wall : float
        Damping coefficients: kg/s for the linear law, kg/(s m^0.5) for
        Hertz–Kuwabara–Kono.
    wall : WallSpec
    """

    beads: int = N_PARTICLES - 1
    bead_diameter_m: float = 2.0 * BEAD_RADIUS
    bead_mass_kg: float = BEAD_MASS
    material: str = BEAD_STEEL.name
    youngs_modulus_pa: float = BEAD_STEEL.youngs_modulus
    poisson_ratio: float = BEAD_STEEL.poisson_ratio
    gravity_m_per_s2: float = G0
    damping: Damping = Damping.LINEAR
    gamma_contact: float = 0.0
    gamma_wall: float = 0.0
    wall: WallSpec = field(default_factory=WallSpec)

    @property
    def n_particles(self) -> int:
        """Particles including the striker."""
        return self.beads + 1


@dataclass(frozen=True)
class InsertSpec:
    """A cylinder (piezo rod) that replaces the bead at ``particle``."""

    particle: int
    kind: str = "rod"
    mass_kg: float = PIEZO_ROD_MASS
    youngs_modulus_pa: float = PIEZO_ROD.youngs_modulus
    poisson_ratio: float = PIEZO_ROD.poisson_ratio
    length_m: float = PIEZO_ROD_LENGTH


@dataclass(frozen=True)
class PrecompressionSpec:
    """A static compression ``force_n`` (N) added to contacts ``first``..``last``.

    Contact c_i joins particles i and i+1 (1-based). The compression is applied as a pair of
    equal and opposite static forces on particles ``first`` and ``last + 1``.
    """

    first: int
    last: int
    force_n: float


@dataclass(frozen=True)
class CoilSpec:
    """Receiver coil wound around the tube, centred on its sensor's particle."""

    turns: int = 1100
    length_m: float = 7e-3
    inner_radius_m: float = 7.95e-3
    wire: str = "AWG36"
    axial_offset_m: float = 0.0
    packing_factor: float | None = None


@dataclass(frozen=True)
class MagnetSpec:
    """Bias magnet: an axially magnetised ring with two steel pole pieces.

    Dimensions left as ``None`` take the field model's documented defaults.
    """

    enabled: bool = True
    grade: str | None = "ceramic8"
    remanence_t: float | None = None
    recoil_permeability: float | None = None
    inner_radius_m: float | None = None
    outer_radius_m: float | None = None
    length_m: float | None = None
    pole_inner_radius_m: float | None = None
    pole_outer_radius_m: float | None = None
    pole_thickness_m: float | None = None
    axial_offset_m: float = 0.0


@dataclass(frozen=True)
class SensorSpec:
    """One sensor at ``particle`` (1-based, striker = 1)."""

    kind: SensorKind
    particle: int
    model: MssModel | None = None
    coil: CoilSpec | None = None
    magnet: MagnetSpec | None = None


@dataclass(frozen=True)
class SetupSpec:
    """One experimental configuration of the chain."""

    name: str
    sensors: tuple[SensorSpec, ...]
    inserts: tuple[InsertSpec, ...] = ()
    precompression: tuple[PrecompressionSpec, ...] = ()


@dataclass(frozen=True)
class StrikerSpec:
    """Striker impact: a drop height (m) or a velocity (m/s)."""

    velocity_m_per_s: float
    drop_height_m: float | None = None


@dataclass(frozen=True)
class SimulationSpec:
    """Time span (s), output sampling (Hz) and optional fixed step (s) of the chain run."""

    t_end_s: float = 1e-3
    sample_rate_hz: float = 10e6
    dt_s: float | None = None


@dataclass(frozen=True)
class FieldSpec:
    """Options of the finite-element field model (all optional).

    Attributes
    ----------
    beads : (int, int) or None
        First and last particle in the field model (default: the whole chain).
    contact_load_n : float or None
        Static load that sets the Hertz contact-flat radius, N.
    min_flat_radius_m, contact_gap_m : float or None
        Lower bound of the flat radius and an air gap between flats, m.
    air_radius_m, air_margin_m : float or None
        Truncation of open space, m.
    steel_bh : BHCurve or None
        User B–H table of the beads and pole pieces (``steel_bh`` = [[B_T, H_A_per_m], ...]);
        None means the field model's default, AISI 1018 (FEMM library). The beads'
        magnetoelastic (JAS) anhysteretic is fitted to the same table
        (:func:`msens.magnetics.steel_law.law_for_steel`).
    eddy_currents : bool
        Physics MsS with eddy currents in the conducting beads and pole pieces: frequency
        dependent sensitivities and coil impedance (:mod:`msens.magnetics.dynamic`) instead
        of the magnetostatic transducer. Off by default (see the README for its accuracy).
    steel_conductivity_s_per_m : float or None
        Electrical conductivity of the beads and pole pieces, S/m; None means
        :data:`msens.field.eddy.SIGMA_1018` (AISI 1018, 6 MS/m, cited there).
    small_signal_permeability : {"differential", "reversible"}
        Permeability of the steel for the signal about the bias point (the transducer's
        sensitivities, the coil's L and Z(f)): the differential slope of the B–H curve, or its
        reversible part c (``reversibility``; :class:`msens.field.regions.NonlinearSoft`).
    reversibility : float or None
        c in (0, 1) with ``"reversible"``; None means
        :data:`msens.params.materials.STEEL_REVERSIBILITY`.
    skin_size_m : float or None
        Element size at the surfaces of the beads near a coil for the eddy-current model, m;
        None means :data:`msens.field.eddy.SKIN_SIZE`.
    contact_map : bool
        Read the contacts near each coil through their nonlinear maps Λ_c(δ) from the open
        gap to the peak approach (:mod:`msens.magnetics.contact_map`) instead of the linear
        approach sources alone. Off by default (cold: about a minute per mapped contact).
    """

    beads: tuple[int, int] | None = None
    contact_load_n: float | None = None
    min_flat_radius_m: float | None = None
    contact_gap_m: float | None = None
    air_radius_m: float | None = None
    air_margin_m: float | None = None
    steel_bh: BHCurve | None = None
    eddy_currents: bool = False
    steel_conductivity_s_per_m: float | None = None
    small_signal_permeability: str = "differential"
    reversibility: float | None = None
    skin_size_m: float | None = None
    contact_map: bool = False

    @property
    def steel_reversibility(self) -> float:
        """The fraction c of the differential susceptibility the signal sees (1 = all)."""
        if self.small_signal_permeability == "differential":
            return 1.0
        from msens.params.materials import STEEL_REVERSIBILITY

        return STEEL_REVERSIBILITY if self.reversibility is None else self.reversibility


@dataclass(frozen=True)
class DissipationFitSpec:
    """Fit γc, γw ≥ 0 to measured amplitude ratios (paper Eq. 10) on ``setup``."""

    setup: str
    ar_top: float
    ar_bottom: float


@dataclass(frozen=True)
class ReferenceRow:
    """A published row to compare with (e.g. paper Table 2): experiment and its model."""

    setup: str
    position: str
    tof_us: float
    tof_std_us: float
    ar: float
    ar_std: float
    model_tof_us: float | None = None
    model_ar: float | None = None
