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
    """The half-space the chain stands on (``[chain.wall]``).

    Attributes
    ----------
    youngs_modulus_pa : float
        Young's modulus of the wall, Pa (the paper gives no wall material: steel assumed).
    poisson_ratio : float
        Poisson's ratio of the wall. Unit: 1.
    """

    youngs_modulus_pa: float = 200e9
    poisson_ratio: float = 0.29


@dataclass(frozen=True)
class ChainSpec:
    """The bead chain below the striker.

    Attributes
    ----------
    beads : int
        Number of beads below the striker (the paper: 29); particles are numbered
        1 (striker) to ``beads + 1`` (on the wall). Unit: count.
    bead_diameter_m, bead_mass_kg : float
        Bead diameter (m) and mass (kg); the striker is an identical bead. Mass and
        diameter must give a density of a solid (100–30,000 kg/m³).
    material : str
        Name of the bead material, for reports (the elastic constants are the keys below).
    youngs_modulus_pa : float
        Young's modulus of the beads, Pa.
    poisson_ratio : float
        Poisson's ratio of the beads. Unit: 1.
    gravity_m_per_s2 : float
        Acceleration of gravity along the chain, toward the wall, m/s² (TOML key
        ``gravity``; 0 for a horizontal chain).
    damping : Damping
        Dissipation law in the contacts: ``"linear"`` (the paper's Eq. 6 dashpot, acting
        both ways), ``"linear-loading"`` (the dashpot acts only while a contact is being
        compressed: with it the paper's γc = 4.8 kg/s reproduces its Table 2) or
        ``"hertz-kuwabara-kono"``.
    gamma_contact, gamma_wall : float
        Damping coefficients of the bead–bead and bead–wall contacts: ``gamma_contact_kg_per_s``
        and ``gamma_wall_kg_per_s`` (kg/s) for the linear laws, ``hkk_contact_kg_per_s_sqrt_m``
        and ``hkk_wall_kg_per_s_sqrt_m`` (kg/(s m^0.5)) for Hertz–Kuwabara–Kono. A dashpot
        time m/(2γ) below 0.1 µs is refused (the chain would carry no wave).
    wall : WallSpec
        The ``[chain.wall]`` table.
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
    """A cylinder (piezo rod) that replaces the bead at ``particle`` (``[[chain.insert]]``).

    Defaults are the paper's rod (Piezo Kinetics, 0.8144 g, 6 mm long).

    Attributes
    ----------
    particle : int
        Particle the rod replaces, from 2 to the last (1 is the striker); two rods may not
        touch and the last particle must be a bead. Unit: particle number.
    kind : str
        ``"rod"``, the only insert the chain model has.
    mass_kg : float
        Mass of the rod, kg.
    youngs_modulus_pa : float
        Young's modulus of the rod, Pa.
    poisson_ratio : float
        Poisson's ratio of the rod. Unit: 1.
    length_m : float
        Length of the rod along the chain, m.
    """

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

    Attributes
    ----------
    first, last : int
        First and last contact compressed, the TOML key ``contacts`` = ``[first, last]`` with
        1 <= first <= last <= the number of contacts. Unit: contact number.
    force_n : float
        Static compression added to each of those contacts, N; its peak Hertz pressure must
        stay below 10 GPa (steels yield above).
    """

    first: int
    last: int
    force_n: float


@dataclass(frozen=True)
class CoilSpec:
    """Receiver coil wound around the tube, centred on its sensor's particle (``[sensor.coil]``).

    Defaults are the paper's coil: 1100 turns of AWG36, 7 mm long, on a former of 12.7 mm
    inner diameter and 1.6 mm wall.

    Attributes
    ----------
    turns : int
        Number of turns. Unit: count.
    length_m : float
        Winding length along the tube, m.
    inner_radius_m : float
        Inner radius of the winding (the former's outer radius), m.
    wire : str
        Wire gauge, ``"AWG10"`` to ``"AWG50"``.
    axial_offset_m : float
        Shift of the coil's centre from its particle's centre, m (+ = up, toward the
        striker), within half a bead diameter.
    packing_factor : float or None
        Fraction of the winding cross-section filled by copper and enamel; none means square
        packing (π/4). At most π/(2√3) = 0.907 (orthocyclic). Unit: 1.
    """

    turns: int = 1100
    length_m: float = 7e-3
    inner_radius_m: float = 7.95e-3
    wire: str = "AWG36"
    axial_offset_m: float = 0.0
    packing_factor: float | None = None


@dataclass(frozen=True)
class MagnetSpec:
    """Bias magnet: an axially magnetised ring with two steel pole pieces (``[sensor.magnet]``).

    The paper's bridge magnet is undocumented: this is its axisymmetric *equivalent*.
    Dimensions left as ``None`` take the field model's documented defaults
    (:class:`msens.field.parts.MagnetAssembly`: ring 12.5/20 mm radii, 16 mm long, pole pieces
    6.5/20 mm radii, 3 mm thick, pole centres 19 mm apart).

    Attributes
    ----------
    enabled : bool
        Whether the coil has a bias magnet (false: the coil reads the beads unbiased).
    grade : str or None
        Magnet grade, ``"ceramic8"`` (default, B_r 0.39 T), ``"N38"`` or ``"N42"``; or give
        ``remanence_T`` and ``recoil_permeability`` instead.
    remanence_t : float or None
        Remanence B_r of the ring magnet, T (TOML key ``remanence_T``).
    recoil_permeability : float or None
        Relative recoil permeability μ_rec of the magnet, given with ``remanence_T``. Unit: 1.
    inner_radius_m, outer_radius_m, length_m : float or None
        Ring magnet's inner and outer radius and axial length, m.
    pole_inner_radius_m, pole_outer_radius_m, pole_thickness_m : float or None
        The two annular AISI 1018 pole pieces' inner and outer radius and thickness, m.
    axial_offset_m : float
        Shift of the assembly's centre from its particle's centre, m (+ = up), within half a
        bead diameter.
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
    """One sensor at ``particle`` (1-based, striker = 1): a ``[[sensor]]`` table.

    Attributes
    ----------
    kind : SensorKind
        ``"bead"`` (an instrumented bead: the mean of its two contact forces), ``"rod"`` (a
        piezo rod, which needs an ``[[chain.insert]]`` at its particle) or ``"mss"`` (a
        magnetostrictive sensor: coil and bias magnet around the tube).
    particle : int
        The sensor's particle, 1-based counting the striker as 1 (the paper's numbering);
        from 2 (3 for an MsS) to the last, one sensor per particle. Unit: particle number.
    model : MssModel or None
        For an MsS: ``"physics"`` (field model, both mechanisms, read-out circuit: volts) or
        ``"four-contact"`` (the paper's hypothesis: the mean of four contact forces).
    coil : CoilSpec or None
        The MsS's ``[sensor.coil]`` table; for an MsS without one, the default coil (the
        paper's), set here once for every reader of the study. None for other sensors.
    magnet : MagnetSpec or None
        The MsS's ``[sensor.magnet]`` table; for an MsS without one, the default magnet.
    """

    kind: SensorKind
    particle: int
    model: MssModel | None = None
    coil: CoilSpec | None = None
    magnet: MagnetSpec | None = None

    def __post_init__(self) -> None:
        if self.kind is SensorKind.MSS:  # the study's defaults, applied once, here
            if self.coil is None:
                object.__setattr__(self, "coil", CoilSpec())
            if self.magnet is None:
                object.__setattr__(self, "magnet", MagnetSpec())


@dataclass(frozen=True)
class SetupSpec:
    """One experimental configuration of the chain (a ``[[setup]]`` table).

    Attributes
    ----------
    name : str
        The setup's name, unique in the study (used by ``--setup`` and in the results).
    sensors, inserts, precompression : tuple
        Its ``[[setup.sensor]]``, ``[[setup.insert]]`` and ``[[setup.precompression]]``
        tables, with the keys of ``[[sensor]]``, ``[[chain.insert]]`` and
        ``[[precompression]]``.
    """

    name: str
    sensors: tuple[SensorSpec, ...]
    inserts: tuple[InsertSpec, ...] = ()
    precompression: tuple[PrecompressionSpec, ...] = ()


@dataclass(frozen=True)
class StrikerSpec:
    """Striker impact: a drop height (m) or a velocity (m/s); give exactly one.

    Attributes
    ----------
    velocity_m_per_s : float
        Striker speed at impact, m/s (given, or √(2 g h) from the drop height).
    drop_height_m : float or None
        Free-fall height of the striker (a bead identical to the chain's) above bead 2, m.
    """

    velocity_m_per_s: float
    drop_height_m: float | None = None


@dataclass(frozen=True)
class SimulationSpec:
    """Time span (s), output sampling (Hz) and optional fixed step (s) of the chain run.

    Attributes
    ----------
    t_end_s : float
        Simulated time after the striker's impact, s; at least 100 output samples and at
        most 5e7.
    sample_rate_hz : float
        Output sampling rate of the chain records (forces, approaches), Hz.
    dt_s : float or None
        Fixed integration step, s; none means the compiled integrator's adaptive default
        (8th-order, about t_c/20 of the contact time).
    """

    t_end_s: float = 1e-3
    sample_rate_hz: float = 10e6
    dt_s: float | None = None


@dataclass(frozen=True)
class FieldSpec:
    """Options of the finite-element field model (all optional).

    Attributes
    ----------
    beads : (int, int) or None
        First and last particle in the field model, ``[first, last]`` with 2 <= first <=
        last <= the last particle (default: the whole chain). Unit: particle number.
    contact_load_n : float or None
        Static load that sets the Hertz contact-flat radius, N.
    min_flat_radius_m, contact_gap_m : float or None
        Lower bound of the flat radius and an air gap between flats, m.
    air_radius_m, air_margin_m : float or None
        Truncation of open space, m.
    steel_bh : BHCurve or None
        User B–H table of the beads and pole pieces (``steel_bh`` = [[B_T, H_A_per_m], ...],
        starting at [0, 0], both columns strictly increasing, B below 5 T);
        None means the field model's default, AISI 1018 (FEMM library). The beads'
        magnetoelastic (JAS) anhysteretic is fitted to the same table
        (:func:`msens.magnetics.steel_law.law_for_steel`). Unit: T, A/m.
    eddy_currents : bool
        Physics MsS with eddy currents in the conducting beads and pole pieces: frequency
        dependent sensitivities and coil impedance (:mod:`msens.magnetics.dynamic`) instead
        of the magnetostatic transducer. Off when the key is absent; the main study
        (``studies/paper-mss.toml``) turns it on, and ``false`` is the faster, less exact
        magnetostatic model (the theory page says what it changes).
    steel_conductivity_s_per_m : float or None
        Electrical conductivity of the beads and pole pieces, S/m; None means
        :data:`msens.params.materials.SIGMA_1018` (AISI 1018, 6 MS/m, cited there).
    small_signal_permeability : {"differential", "reversible"}
        Permeability of the steel for the signal about the bias point (the transducer's
        sensitivities, the coil's L and Z(f)): the differential slope of the B–H curve, or its
        reversible part c (``reversibility``; :class:`msens.field.regions.NonlinearSoft`).
    reversibility : float or None
        c in (0, 1) with ``"reversible"``; None means
        :data:`msens.params.materials.STEEL_REVERSIBILITY` (0.1, an estimate quoted for
        steels). Unit: 1.
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
    """Fit γc, γw ≥ 0 to measured amplitude ratios (paper Eq. 10) on ``setup``.

    The ``[calibration.dissipation]`` table.

    Attributes
    ----------
    setup : str
        The two-sensor setup whose measured amplitude ratios are fitted.
    ar_top, ar_bottom : float
        Measured amplitude ratio (reflected over incident peak) at the top and the bottom
        sensor. Unit: 1.
    """

    setup: str
    ar_top: float
    ar_bottom: float


@dataclass(frozen=True)
class ReferenceRow:
    """A published row to compare with (e.g. paper Table 2): experiment and its model.

    A ``[[reference.row]]`` table.

    Attributes
    ----------
    setup : str
        The setup the row belongs to.
    position : str
        ``"top"`` or ``"bottom"`` sensor of that setup.
    tof_us, tof_std_us : float
        Measured time of flight between incident and reflected pulse and its standard
        deviation, µs.
    ar, ar_std : float
        Measured amplitude ratio and its standard deviation. Unit: 1.
    model_tof_us : float or None
        The publication's own model TOF, µs.
    model_ar : float or None
        The publication's own model AR. Unit: 1.
    """

    setup: str
    position: str
    tof_us: float
    tof_std_us: float
    ar: float
    ar_std: float
    model_tof_us: float | None = None
    model_ar: float | None = None
