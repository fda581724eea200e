"""Study files (TOML, schema ``msens.study/1``) parsed once into frozen dataclasses.

This module is the single place where a study's input is validated: every later stage
receives typed, checked values. A study describes one chain (beads, wall, striker) and one
or more *setups* — the sensors, inserted rods and static precompressions of one experiment.
A plain study has its ``[[sensor]]``, ``[[chain.insert]]`` and ``[[precompression]]`` at top
level (one setup, named after the study); a comparison study such as the paper's Table 2
lists ``[[setup]]`` tables instead, each with its own ``sensor``/``insert``/``precompression``.

Units are SI throughout and appear in the key names.
"""

from __future__ import annotations

import copy
import enum
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from msens.chain.model import DampingLaw as Damping
from msens.config import plausible as P
from msens.errors import InputError
from msens.io.tomlreader import Table, document_table, read_document
from msens.params.materials import (
    BEAD_STEEL,
    MAGNET_GRADES,
    PIEZO_ROD,
    PIEZO_ROD_LENGTH,
    PIEZO_ROD_MASS,
    BHCurve,
)
from msens.params.units import G0, MU0
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

    beads: int = 29
    bead_diameter_m: float = 4.76e-3
    bead_mass_kg: float = 0.45e-3
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
class ElectronicsSpec:
    """Coil read-out chain. Capacitances in F, resistance in Ohm, rate in Hz.

    Defaults: 1 m of RG-58 coaxial cable (about 100 pF/m) into a 1 MOhm || 20 pF DAQ input
    sampled at the paper's 10 MHz; noise off unless asked for.
    """

    cable_capacitance_f: float = 100e-12
    input_resistance_ohm: float = 1e6
    input_capacitance_f: float = 20e-12
    sample_rate_hz: float = 10e6
    johnson_noise: bool = False
    temperature_k: float = 293.15
    adc_bits: int | None = None
    adc_range_v: float | None = None
    input_noise_v_per_rthz: float = 0.0
    seed: int = 0


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
        None means :data:`msens.magnetics.dynamic.SKIN_SIZE`.
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


@dataclass(frozen=True)
class Study:
    """A validated study."""

    name: str
    chain: ChainSpec
    striker: StrikerSpec
    setups: tuple[SetupSpec, ...]
    simulation: SimulationSpec = field(default_factory=SimulationSpec)
    electronics: ElectronicsSpec = field(default_factory=ElectronicsSpec)
    field: FieldSpec = field(default_factory=FieldSpec)
    dissipation_fit: DissipationFitSpec | None = None
    reference: tuple[ReferenceRow, ...] = ()
    measurement_file: Path | None = None
    source: str = "<memory>"

    def setup(self, name: str) -> SetupSpec:
        """The setup called ``name``."""
        for s in self.setups:
            if s.name == name:
                return s
        raise KeyError(name)

    def replace(self, changes: Mapping[str, Any] | None = None, /, **more: Any) -> Study:
        """This study with some keys of its TOML changed, validated exactly like a file.

        Parameters
        ----------
        changes : Mapping[str, Any], optional
            Dotted key -> new value, the keys spelled as msens's messages name them:
            ``"striker.drop_height_m"``, ``"sensor[1].coil.turns"`` (``[[...]]`` arrays are
            indexed from 1: ``sensor[1]`` is the first ``[[sensor]]``),
            ``"setup[3].sensor[2].coil.turns"``. A value is a number, string, boolean, list
            or dict (a whole table); None removes the key (e.g. to give
            ``striker.velocity_m_per_s`` instead of ``striker.drop_height_m``). Tables that
            are missing are created.
        **more
            More changes, e.g. ``**{"striker.drop_height_m": 0.01}``.

        Returns
        -------
        Study
            A new study; this one is unchanged.

        Raises
        ------
        InputError
            For a key that does not fit the document (an index out of range, a value where
            a table is needed), or, from the validation, an unknown key or a value out of
            range, each naming the key.
        """
        return replace_study(self, {**(changes or {}), **more})


# --------------------------------------------------------------------------- parsing

def load_study(path: str | Path) -> Study:
    """Read and validate a study file.

    Parameters
    ----------
    path : str or Path
        A ``.toml`` file following schema ``msens.study/1``.

    Raises
    ------
    InputError
        Missing or unreadable file, bad TOML, or any invalid key or value.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise InputError(f"study file '{path}' does not exist") from None
    except IsADirectoryError:
        raise InputError(f"study file '{path}' is a directory, expected a .toml file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"study file '{path}' cannot be read: {exc}") from None
    return parse_study(text, source=str(path), base_dir=path.parent)


def builtin_study_path(name: str) -> Path:
    """A study shipped with the package (``paper-mss``, ``paper-table2``)."""
    return Path(str(resources.files("msens") / "data" / f"{name}.toml"))


def default_study_path() -> Path:
    """The built-in default study of ``msens run``."""
    return builtin_study_path(DEFAULT_STUDY)


def parse_study(text: str, *, source: str = "<memory>", base_dir: Path | None = None) -> Study:
    """Validate the TOML ``text`` of a study (see :func:`load_study`)."""
    return _study(read_document(text, source=source, schema=SCHEMA), source, base_dir)


def _study(root: Table, source: str, base_dir: Path | None) -> Study:
    name = root.string("name", required=True)
    chain_t = root.table("chain", required=True)
    chain = _chain(chain_t)
    top_inserts = chain_t.tables("insert")
    chain_t.finish()
    striker = _striker(root.table("striker", required=True))
    setups = _setups(root, chain, name, top_inserts)
    simulation = _simulation(root.table("simulation"))
    electronics = _electronics(root.table("electronics"))
    field_spec = _field(root.table("field"), chain, source)
    calib = root.table("calibration")
    fit = _dissipation_fit(calib, setups) if calib is not None else None
    reference = _reference(root.table("reference"), setups)
    measurement_file = _measurement(root.table("measurement"), base_dir)
    root.finish()
    study = Study(name=name, chain=chain, striker=striker, setups=setups,
                  simulation=simulation, electronics=electronics, field=field_spec,
                  dissipation_fit=fit, reference=reference,
                  measurement_file=measurement_file, source=source)
    # The parsed document rides beside the fields, not as one: the content hash and the
    # design cache keys are of the validated values only. Study.replace re-validates it.
    object.__setattr__(study, "_document", (root.data, base_dir))
    return study


# --------------------------------------------------------------------------- replace

#: One segment of a dotted key: a name, optionally with a 1-based array index.
_SEGMENT = re.compile(r"([^.\[\]\s]+)(?:\[(-?[0-9]+)\])?")


def replace_study(study: Study, changes: Mapping[str, Any]) -> Study:
    """``study`` with keys of its TOML document changed (see :meth:`Study.replace`).

    The changes are applied to a copy of the parsed document, which then goes through the
    same validation as a file, so a replaced study can hold nothing a file could not.
    """
    state = getattr(study, "_document", None)
    if state is None:
        raise InputError(f"study {study.name!r} was not read from a study file (load_study, "
                         "parse_study), so it has no keys to replace")
    document, base_dir = state
    if not changes:
        return study
    doc = copy.deepcopy(document)
    for key, value in changes.items():
        _set_key(doc, key, value, study.source)
    listed = ", ".join(f"{k}={_short(None if v is None else _toml_value(v, k, study.source))}"
                       for k, v in changes.items())
    source = f"{study.source} with {listed}"
    return _study(document_table(doc, source=source, schema=SCHEMA), source, base_dir)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _set_key(doc: dict, key: object, value: Any, source: str) -> None:
    """Set (or, for None, remove) the dotted ``key`` in the document ``doc``."""
    if not isinstance(key, str) or not key:
        raise InputError(f"{source}: replace key {key!r} must be a dotted key such as "
                         "'striker.drop_height_m'")
    segments = []
    for part in key.split("."):
        match = _SEGMENT.fullmatch(part)
        if match is None:
            raise InputError(f"{source}: replace key {key!r}: bad part {part!r}; keys are "
                             "names joined by dots, arrays of tables indexed from 1 "
                             "('sensor[1].coil.turns')")
        segments.append((match.group(1), None if match.group(2) is None
                         else int(match.group(2))))
    node: dict = doc
    done = ""
    for n, (name, index) in enumerate(segments):
        last = n == len(segments) - 1
        path = f"{done}.{name}" if done else name
        here = node.get(name)
        if index is not None:
            if not isinstance(here, list) or not all(isinstance(t, dict) for t in here):
                raise InputError(f"{source}: replace key {key!r}: '{path}' is not an array of "
                                 f"tables ([[{path}]]) in this study")
            if not 1 <= index <= len(here):
                hint = (" (indices count from 1, as msens's messages name them: "
                        f"{path}[1] is the first)" if index == 0 else "")
                raise InputError(f"{source}: replace key {key!r}: the study has {len(here)} "
                                 f"[[{path}]] table(s), {path}[1] to {path}[{len(here)}], "
                                 f"not {path}[{index}]{hint}")
            if last:
                if not isinstance(value, Mapping):
                    raise InputError(f"{source}: replace key {key!r}: a [[{path}]] table is "
                                     f"replaced by a dict, got {value!r}")
                here[index - 1] = _toml_value(value, key, source)
                return
            node, done = here[index - 1], f"{path}[{index}]"
            continue
        if last:
            if value is None:
                if name not in node:
                    raise InputError(f"{source}: replace key {key!r}: nothing to remove, "
                                     f"'{path}' is not in the study")
                del node[name]
            else:
                node[name] = _toml_value(value, key, source)
            return
        if here is None:
            here = node[name] = {}  # an optional table the file left out
        if isinstance(here, list):
            raise InputError(f"{source}: replace key {key!r}: '{path}' is an array of "
                             f"{len(here)} table(s): give an index, e.g. '{path}[1]'")
        if not isinstance(here, dict):
            raise InputError(f"{source}: replace key {key!r}: '{path}' is a value "
                             f"({here!r}), not a table")
        node, done = here, path


def _toml_value(value: Any, key: str, source: str) -> Any:
    """``value`` as TOML would give it (numpy scalars and arrays, tuples and paths become
    Python numbers, lists and strings), for the validation to judge."""
    if isinstance(value, np.generic | np.ndarray):  # before float: np.float64 is one
        return _toml_value(value.tolist(), key, source)
    if isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, list | tuple):
        return [_toml_value(v, key, source) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _toml_value(v, key, source) for k, v in value.items()}
    raise InputError(f"{source}: replace key {key!r}: {value!r} is not a TOML value (a "
                     "number, string, boolean, list or dict)")


def _chain(t: Table) -> ChainSpec:
    d = ChainSpec()
    damping = t.string("damping", d.damping.value, choices=[m.value for m in Damping])
    law = Damping(damping)
    # The linear law's coefficients are in kg/s, the HKK law's in kg/(s m^0.5): distinct keys
    # keep a number from being read in the wrong unit.
    if law in (Damping.LINEAR, Damping.LINEAR_LOADING):
        gc = t.number("gamma_contact_kg_per_s", 0.0, low=0.0)
        gw = t.number("gamma_wall_kg_per_s", 0.0, low=0.0)
    else:
        gc = t.number("hkk_contact_kg_per_s_sqrt_m", 0.0, low=0.0)
        gw = t.number("hkk_wall_kg_per_s_sqrt_m", 0.0, low=0.0)
    wall_t = t.table("wall")
    wall = WallSpec()
    if wall_t is not None:
        wall = WallSpec(
            youngs_modulus_pa=_modulus(wall_t, wall.youngs_modulus_pa),
            poisson_ratio=wall_t.number("poisson_ratio", wall.poisson_ratio, low=-1.0,
                                        high=0.5, low_open=True),
        )
        wall_t.finish()
    diameter = t.number("bead_diameter_m", d.bead_diameter_m, low=P.BEAD_DIAMETER_M[0],
                        high=P.BEAD_DIAMETER_M[1])
    mass = t.number("bead_mass_kg", d.bead_mass_kg, low=0.0, low_open=True)
    density = mass / (math.pi / 6.0 * diameter**3)
    lo, hi = P.BEAD_DENSITY_KG_PER_M3
    if not lo <= density <= hi:
        raise t.error("bead_mass_kg", f"= {mass:g} kg with bead_diameter_m = {diameter:g} m "
                                      f"is a bead density of {density:.3g} kg/m^3; solids lie "
                                      f"between {lo:g} and {hi:g} kg/m^3 (a typo in the mass "
                                      "or the diameter?)")
    for key, value in (("gamma_contact_kg_per_s" if law is not Damping.HERTZ_KUWABARA_KONO
                        else "hkk_contact_kg_per_s_sqrt_m", gc),
                       ("gamma_wall_kg_per_s" if law is not Damping.HERTZ_KUWABARA_KONO
                        else "hkk_wall_kg_per_s_sqrt_m", gw)):
        _check_dashpot(t, key, value, mass, law)
    return ChainSpec(
        beads=t.integer("beads", d.beads, low=P.BEADS[0], high=P.BEADS[1]),
        bead_diameter_m=diameter,
        bead_mass_kg=mass,
        material=t.string("material", d.material),
        youngs_modulus_pa=_modulus(t, d.youngs_modulus_pa),
        poisson_ratio=t.number("poisson_ratio", d.poisson_ratio, low=-1.0, high=0.5,
                               low_open=True),
        gravity_m_per_s2=t.number("gravity", d.gravity_m_per_s2, low=P.GRAVITY_M_PER_S2[0],
                                  high=P.GRAVITY_M_PER_S2[1]),
        damping=law, gamma_contact=gc, gamma_wall=gw, wall=wall,
    )


def _modulus(t: Table, default: float) -> float:
    """``youngs_modulus_pa`` of table ``t`` within
    :data:`msens.config.plausible.YOUNGS_MODULUS_PA`."""
    return t.number("youngs_modulus_pa", default, low=P.YOUNGS_MODULUS_PA[0],
                    high=P.YOUNGS_MODULUS_PA[1])


def _check_dashpot(t: Table, key: str, gamma: float, mass: float, law: Damping) -> None:
    """Refuse a damping coefficient whose dashpot time m/(2 gamma) is below
    :data:`msens.config.plausible.MIN_DASHPOT_TIME_S` (see there why)."""
    hkk = law is Damping.HERTZ_KUWABARA_KONO
    scale = math.sqrt(P.HKK_REFERENCE_APPROACH_M) if hkk else 1.0  # to kg/s
    high = 0.5 * mass / P.MIN_DASHPOT_TIME_S
    if gamma * scale > high:
        limit = high / scale
        raise t.error(key, f"must be <= {limit:.3g} for beads of {mass:g} kg, got {gamma:g}: "
                           f"its dashpot would stop a bead in under "
                           f"{P.MIN_DASHPOT_TIME_S:g} s, faster than any bead contact "
                           "vibrates (the chain would carry no wave)")


def _striker(t: Table) -> StrikerSpec:
    has_h, has_v = t.has("drop_height_m"), t.has("velocity_m_per_s")
    if has_h == has_v:
        raise t.error("drop_height_m", "or 'striker.velocity_m_per_s': give exactly one")
    if has_h:
        h = t.number("drop_height_m", low=P.DROP_HEIGHT_M[0], high=P.DROP_HEIGHT_M[1])
        t.finish()
        return StrikerSpec(velocity_m_per_s=math.sqrt(2.0 * G0 * h), drop_height_m=h)
    v = t.number("velocity_m_per_s", low=P.STRIKER_VELOCITY_M_PER_S[0],
                 high=P.STRIKER_VELOCITY_M_PER_S[1])
    t.finish()
    return StrikerSpec(velocity_m_per_s=v)


def _particle(t: Table, name: str, chain: ChainSpec, *, first: int = 2) -> int:
    n = chain.n_particles
    p = t.integer(name, required=True)
    if not first <= p <= n:
        raise t.error(name, f"must be a particle from {first} to {n} (1 is the striker, "
                            f"{n} stands on the wall), got {p}")
    return p


def _insert(t: Table, chain: ChainSpec) -> InsertSpec:
    d = InsertSpec(particle=0)
    spec = InsertSpec(
        particle=_particle(t, "particle", chain),
        kind=t.string("kind", "rod", choices=["rod"]),
        mass_kg=t.number("mass_kg", d.mass_kg, low=0.0, high=100.0, low_open=True),
        youngs_modulus_pa=_modulus(t, d.youngs_modulus_pa),
        poisson_ratio=t.number("poisson_ratio", d.poisson_ratio, low=-1.0, high=0.5,
                               low_open=True),
        length_m=t.number("length_m", d.length_m, low=0.0, high=1.0, low_open=True),
    )
    t.finish()
    return spec


def _precompression(t: Table, chain: ChainSpec) -> PrecompressionSpec:
    contacts = t.raw("contacts")
    n = chain.n_particles
    ok = (isinstance(contacts, list) and len(contacts) == 2
          and all(isinstance(c, int) and not isinstance(c, bool) for c in contacts))
    if not ok or not 1 <= contacts[0] <= contacts[1] <= n - 1:
        raise t.error("contacts", f"must be [first, last] contact numbers with "
                                  f"1 <= first <= last <= {n - 1}, got {contacts!r}")
    force = t.number("force_N", required=True, low=0.0, high=1e6)  # 1 MN crushes any bead
    _check_static_load(t, "force_N", force, chain)
    t.finish()
    return PrecompressionSpec(first=contacts[0], last=contacts[1], force_n=force)


def _check_static_load(t: Table, key: str, force: float, chain: ChainSpec) -> None:
    """Refuse a static contact load that would yield the beads: Hertz's law, which the chain
    and field models use, holds only below
    :data:`msens.config.plausible.MAX_CONTACT_PRESSURE_PA`."""
    if force <= 0.0:
        return
    from msens.mechanics.beadstress import hertz_contact  # scikit-fem: only when a load is given

    _, p0 = hertz_contact(chain.bead_diameter_m / 2.0, chain.youngs_modulus_pa,
                          chain.poisson_ratio, force)
    if not p0 <= P.MAX_CONTACT_PRESSURE_PA:  # also NaN: the force overflowed
        raise t.error(key, f"= {force:g} N presses two beads with a peak Hertz pressure of "
                           f"{p0 / 1e9:.3g} GPa, above the {P.MAX_CONTACT_PRESSURE_PA / 1e9:g} "
                           "GPa where steels yield (Hertz contact, which the models assume, "
                           "no longer holds)")


def _offset(t: Table, chain: ChainSpec) -> float:
    """``axial_offset_m`` of a coil or magnet: within half a bead of its particle."""
    high = P.MAX_AXIAL_OFFSET_BEADS * chain.bead_diameter_m
    offset = t.number("axial_offset_m", 0.0)
    if abs(offset) > high:
        raise t.error("axial_offset_m", f"must be within +-{high:g} m (half a bead "
                                        f"diameter) of its particle, got {offset:g} m: "
                                        "further, it sits nearer the next particle; name that "
                                        "particle instead")
    return offset


def _coil(t: Table, chain: ChainSpec) -> CoilSpec:
    d = CoilSpec()
    spec = CoilSpec(
        turns=t.integer("turns", d.turns, low=1, high=10**6),
        length_m=t.number("length_m", d.length_m, low=P.SENSOR_SIZE_M[0],
                          high=P.SENSOR_SIZE_M[1]),
        inner_radius_m=t.number("inner_radius_m", d.inner_radius_m, low=P.SENSOR_SIZE_M[0],
                                high=P.SENSOR_SIZE_M[1]),
        wire=t.string("wire", d.wire),
        axial_offset_m=_offset(t, chain),
        packing_factor=t.number("packing_factor", None, low=0.0, high=0.907, low_open=True,
                                allow_none=True),
    )
    if not spec.wire.upper().startswith("AWG") or not spec.wire[3:].isdigit() \
            or not 10 <= int(spec.wire[3:]) <= 50:
        raise t.error("wire", f"must be an AWG gauge from 'AWG10' to 'AWG50', got {spec.wire!r}")
    t.finish()
    return spec


def _magnet(t: Table, chain: ChainSpec) -> MagnetSpec:
    dims = {}
    for key in ("inner_radius_m", "outer_radius_m", "length_m", "pole_inner_radius_m",
                "pole_outer_radius_m", "pole_thickness_m"):
        dims[key] = t.number(key, None, low=P.SENSOR_SIZE_M[0], high=P.SENSOR_SIZE_M[1],
                             allow_none=True)
    grade = t.string("grade", None, choices=sorted(MAGNET_GRADES))
    br = t.number("remanence_T", None, low=0.0, high=2.0, low_open=True, allow_none=True)
    mu = t.number("recoil_permeability", None, low=1.0, high=100.0, allow_none=True)
    if grade is not None and (br is not None or mu is not None):
        raise t.error("grade", "cannot be combined with remanence_T/recoil_permeability: "
                               "give a grade or both values")
    if grade is None and (br is None or mu is None):
        if br is None and mu is None:
            grade = "ceramic8"
        else:
            raise t.error("remanence_T", "and 'recoil_permeability' must be given together")
    spec = MagnetSpec(enabled=t.boolean("enabled", True), grade=grade, remanence_t=br,
                      recoil_permeability=mu,
                      axial_offset_m=_offset(t, chain),
                      **dims)
    t.finish()
    return spec


def _sensor(t: Table, chain: ChainSpec) -> SensorSpec:
    kind = SensorKind(t.string("kind", required=True, choices=[k.value for k in SensorKind]))
    particle = _particle(t, "particle", chain, first=3 if kind is SensorKind.MSS else 2)
    model = coil = magnet = None
    if kind is SensorKind.MSS:
        model = MssModel(t.string("model", MssModel.FOUR_CONTACT.value,
                                  choices=[m.value for m in MssModel]))
        if model is MssModel.FOUR_CONTACT and particle > chain.n_particles - 1:
            raise t.error("particle", f"of a four-contact MsS must be at most "
                                      f"{chain.n_particles - 1}, got {particle}")
        ct, mt = t.table("coil"), t.table("magnet")
        coil = _coil(ct, chain) if ct is not None else CoilSpec()
        magnet = _magnet(mt, chain) if mt is not None else MagnetSpec()
    t.finish()
    return SensorSpec(kind=kind, particle=particle, model=model, coil=coil, magnet=magnet)


def _setup(t: Table, name: str, chain: ChainSpec, inserts: list[Table],
           sensors: list[Table], pre: list[Table]) -> SetupSpec:
    ins = tuple(_insert(i, chain) for i in inserts)
    sens = tuple(_sensor(s, chain) for s in sensors)
    if not sens:
        raise t.error("sensor", "is missing: a setup needs at least one [[sensor]]")
    seen: dict[int, SensorKind] = {}
    for s in sens:
        if s.particle in seen:
            # two sensors on one particle read the same force: Eq. 10 and the wave speed
            # would take one particle as both top and bottom
            raise t.error("sensor", f"lists {seen[s.particle].value}@{s.particle} and "
                                    f"{s.kind.value}@{s.particle}: one sensor per particle")
        seen[s.particle] = s.kind
    rods = {i.particle for i in ins}
    if len(rods) != len(ins):
        raise t.error("insert", "replaces the same particle twice")
    # the chain model has sphere-sphere and sphere-flat contacts only
    for r in sorted(rods):
        if r + 1 in rods:
            raise t.error("insert", f"rods at particles {r} and {r + 1} touch flat on flat, "
                                    "which the chain model does not have; keep a bead "
                                    "between two rods")
    if chain.n_particles in rods:
        raise t.error("insert", f"rod at particle {chain.n_particles} would stand on the "
                                "wall (flat on flat, not modelled); the last particle must "
                                "be a bead")
    for s in sens:
        if s.kind is SensorKind.ROD and s.particle not in rods:
            raise t.error("sensor", f"rod sensor at particle {s.particle} needs an "
                                    f"[[insert]] rod at that particle")
    return SetupSpec(name=name, sensors=sens, inserts=ins,
                     precompression=tuple(_precompression(p, chain) for p in pre))


def _setups(root: Table, chain: ChainSpec, name: str,
            top_inserts: list[Table]) -> tuple[SetupSpec, ...]:
    setup_tables = root.tables("setup")
    sensors, pre = root.tables("sensor"), root.tables("precompression")
    if setup_tables:
        if sensors or pre or top_inserts:
            raise root.error("setup", "cannot be combined with top-level [[sensor]], "
                                      "[[precompression]] or [[chain.insert]]")
        out = []
        for st in setup_tables:
            sname = st.string("name", required=True)
            out.append(_setup(st, sname, chain, st.tables("insert"), st.tables("sensor"),
                              st.tables("precompression")))
            st.finish()
        names = [s.name for s in out]
        if len(set(names)) != len(names):
            raise root.error("setup", f"names must be unique, got {names}")
        return tuple(out)
    return (_setup(root, name, chain, top_inserts, sensors, pre),)


def _simulation(t: Table | None) -> SimulationSpec:
    if t is None:
        return SimulationSpec()
    d = SimulationSpec()
    spec = SimulationSpec(
        # a solitary wave needs ~10 us to cross a mm bead: a shorter run sees nothing
        t_end_s=t.number("t_end_s", d.t_end_s, low=1e-6, high=1.0),
        sample_rate_hz=t.number("sample_rate_hz", d.sample_rate_hz, low=P.SAMPLE_RATE_HZ[0],
                                high=P.SAMPLE_RATE_HZ[1]),
        dt_s=t.number("dt_s", None, low=P.DT_S[0], high=P.DT_S[1], allow_none=True),
    )
    if spec.t_end_s * spec.sample_rate_hz > 5e7:
        raise t.error("t_end_s", "times sample_rate_hz gives more than 5e7 samples")
    if spec.t_end_s * spec.sample_rate_hz < 100:  # no pulse can be resolved in fewer
        raise t.error("t_end_s", f"= {spec.t_end_s:g} s at sample_rate_hz = "
                                 f"{spec.sample_rate_hz:g} Hz gives fewer than 100 samples")
    t.finish()
    return spec


def _electronics(t: Table | None) -> ElectronicsSpec:
    if t is None:
        return ElectronicsSpec()
    d = ElectronicsSpec()
    spec = ElectronicsSpec(
        cable_capacitance_f=t.number("cable_capacitance_F", d.cable_capacitance_f,
                                     low=P.CAPACITANCE_F[0], high=P.CAPACITANCE_F[1]),
        input_resistance_ohm=t.number("input_resistance_ohm", d.input_resistance_ohm,
                                      low=P.INPUT_RESISTANCE_OHM[0],
                                      high=P.INPUT_RESISTANCE_OHM[1]),
        input_capacitance_f=t.number("input_capacitance_F", d.input_capacitance_f,
                                     low=P.CAPACITANCE_F[0], high=P.CAPACITANCE_F[1]),
        sample_rate_hz=t.number("sample_rate_hz", d.sample_rate_hz, low=P.SAMPLE_RATE_HZ[0],
                                high=P.SAMPLE_RATE_HZ[1]),
        johnson_noise=t.boolean("johnson_noise", d.johnson_noise),
        temperature_k=t.number("temperature_K", d.temperature_k, low=0.0, high=1000.0),
        adc_bits=t.integer("adc_bits", 0, low=0, high=32) or None,
        adc_range_v=t.number("adc_range_V", None, low=P.ADC_RANGE_V[0],
                             high=P.ADC_RANGE_V[1], allow_none=True),
        input_noise_v_per_rthz=t.number("input_noise_V_per_rtHz", 0.0, low=0.0, high=1e-3),
        seed=t.integer("seed", 0, low=P.SEED[0], high=P.SEED[1]),
    )
    if (spec.adc_bits is None) != (spec.adc_range_v is None):
        raise t.error("adc_bits", "and 'adc_range_V' must be given together")
    t.finish()
    return spec


def _field(t: Table | None, chain: ChainSpec, source: str) -> FieldSpec:
    if t is None:
        return FieldSpec()
    beads = t.raw("beads")
    n = chain.n_particles
    if beads is not None:
        ok = (isinstance(beads, list) and len(beads) == 2
              and all(isinstance(b, int) and not isinstance(b, bool) for b in beads))
        if not ok or not 2 <= beads[0] <= beads[1] <= n:
            raise t.error("beads", f"must be [first, last] particles with 2 <= first <= "
                                   f"last <= {n}, got {beads!r}")
        beads = (beads[0], beads[1])

    def opt(key: str, high: float) -> float | None:
        return t.number(key, None, low=0.0, high=high, allow_none=True)

    load = opt("contact_load_N", 1e4)
    if load is not None:
        _check_static_load(t, "contact_load_N", load, chain)
    spec = FieldSpec(beads=beads, contact_load_n=load,
                     min_flat_radius_m=opt("min_flat_radius_m", 1e-2),
                     contact_gap_m=opt("contact_gap_m", 1e-3),
                     air_radius_m=opt("air_radius_m", 100.0),
                     air_margin_m=opt("air_margin_m", 100.0),
                     steel_bh=_steel_bh(t, source),
                     eddy_currents=t.boolean("eddy_currents", False),
                     # steels lie between ~1 MS/m (stainless) and ~10 MS/m (pure iron)
                     steel_conductivity_s_per_m=t.number("steel_conductivity_S_per_m", None,
                                                         low=1e5, high=2e7,
                                                         allow_none=True),
                     small_signal_permeability=t.string(
                         "small_signal_permeability", "differential",
                         choices=("differential", "reversible")),
                     # c -> 0 would make the steel non-magnetic for the signal; 1 is the
                     # differential slope ("differential")
                     reversibility=t.number("reversibility", None, low=0.01, high=1.0,
                                            allow_none=True),
                     # below 1 µm the mesh explodes; above 1 mm it is no refinement of a 2.4 mm
                     # bead
                     skin_size_m=t.number("skin_size_m", None, low=1e-6, high=1e-3,
                                          allow_none=True))
    if spec.skin_size_m is not None and not spec.eddy_currents:
        raise t.error("skin_size_m", "applies only with eddy_currents = true")
    if spec.reversibility is not None and spec.small_signal_permeability != "reversible":
        raise t.error("reversibility", "applies only with small_signal_permeability = "
                                       "\"reversible\"")
    t.finish()
    return spec


#: Largest flux density accepted in a B–H table, T (iron-cobalt alloys saturate near 2.4 T;
#: B = 5 T would need H of order 2e6 A/m, far beyond any sensor's field).
BH_MAX_B = 5.0
#: Smallest slope ΔH/ΔB of a table's last interval, A/(m T): the field model joins the table to
#: the saturation line B = B_n + μ0 (H − H_n) with a monotone cubic, which needs the last secant
#: to be at least 1/(3 μ0) (Fritsch–Carlson bound; see msens.field.bh.monotone_bh).
BH_MIN_LAST_SLOPE = 1.0 / (3.0 * MU0)


def _steel_bh(t: Table, source: str) -> BHCurve | None:
    """``field.steel_bh``: [[B_T, H_A_per_m], ...] from (0, 0), both strictly increasing."""
    raw = t.raw("steel_bh")
    if raw is None:
        return None
    key = "steel_bh"
    if not isinstance(raw, list) or len(raw) < 3:
        got = f"{len(raw)} pair(s)" if isinstance(raw, list) else repr(raw)
        raise t.error(key, f"must be an array of at least 3 pairs [[B_T, H_A_per_m], ...], "
                           f"got {got}")
    rows = []
    for i, pair in enumerate(raw):
        ok = (isinstance(pair, list) and len(pair) == 2
              and all(isinstance(v, int | float) and not isinstance(v, bool) for v in pair)
              and all(math.isfinite(v) for v in pair))
        if not ok:
            raise t.error(f"{key}[{i}]", f"must be a pair of finite numbers [B_T, H_A_per_m], "
                                         f"got {pair!r}")
        rows.append((float(pair[0]), float(pair[1])))
    if rows[0] != (0.0, 0.0):
        raise t.error(f"{key}[0]", f"must be [0, 0] (the curve starts at the origin), got "
                                   f"{list(raw[0])!r}")
    for i in range(1, len(rows)):
        (b0, h0), (b1, h1) = rows[i - 1], rows[i]
        if not b1 > b0:
            raise t.error(f"{key}[{i}]", f"B must be strictly increasing: B = {b1} T follows "
                                         f"{b0} T")
        if not h1 > h0:
            raise t.error(f"{key}[{i}]", f"H must be strictly increasing: H = {h1} A/m follows "
                                         f"{h0} A/m")
        if not b1 < BH_MAX_B:
            raise t.error(f"{key}[{i}]", f"B must be below {BH_MAX_B} T, got {b1} T")
    (b0, h0), (b1, h1) = rows[-2], rows[-1]
    if (h1 - h0) / (b1 - b0) < BH_MIN_LAST_SLOPE:
        raise t.error(f"{key}[{len(rows) - 1}]",
                      f"ends too steeply: the last interval's dH/dB = {(h1 - h0) / (b1 - b0):.4g} "
                      f"A/(m T) must be at least 1/(3 mu0) = {BH_MIN_LAST_SLOPE:.4g} A/(m T) to "
                      f"join the saturation line; extend the table to higher fields")
    b, h = (np.array(c) for c in zip(*rows, strict=True))
    b.flags.writeable = False
    h.flags.writeable = False
    return BHCurve(name="user table", b=b, h=h, source=source)


def _two_sensor_setup(t: Table, key: str, setups: tuple[SetupSpec, ...]) -> str:
    name = t.string(key, required=True)
    names = [s.name for s in setups]
    if name not in names:
        raise t.error(key, f"must name a setup ({', '.join(names)}), got {name!r}")
    return name


def _dissipation_fit(t: Table, setups: tuple[SetupSpec, ...]) -> DissipationFitSpec | None:
    dt = t.table("dissipation")
    t.finish()
    if dt is None:
        return None
    setup = _two_sensor_setup(dt, "setup", setups)
    spec = DissipationFitSpec(
        setup=setup,
        ar_top=dt.number("ar_top", required=True, low=0.0, high=1.0, low_open=True),
        ar_bottom=dt.number("ar_bottom", required=True, low=0.0, high=1.0, low_open=True),
    )
    dt.finish()
    if len(next(s for s in setups if s.name == setup).sensors) < 2:
        raise dt.error("setup", f"{setup!r} needs two sensors (top and bottom) for Eq. 10")
    return spec


def _reference(t: Table | None, setups: tuple[SetupSpec, ...]) -> tuple[ReferenceRow, ...]:
    if t is None:
        return ()
    rows = []
    for rt in t.tables("row"):
        rows.append(ReferenceRow(
            setup=_two_sensor_setup(rt, "setup", setups),
            position=rt.string("position", required=True, choices=["top", "bottom"]),
            # a time of flight and an amplitude ratio are > 0 (errors are relative to them);
            # an AR below 1e-3 is a pulse lost in any instrument's noise, one above 10 a
            # pulse grown tenfold in a dissipative chain; a TOF of 1 s is a 300 m chain
            tof_us=rt.number("tof_us", required=True, low=0.0, high=1e6, low_open=True),
            tof_std_us=rt.number("tof_std_us", 0.0, low=0.0, high=1e6),
            ar=rt.number("ar", required=True, low=1e-3, high=10.0),
            ar_std=rt.number("ar_std", 0.0, low=0.0, high=10.0),
            model_tof_us=rt.number("model_tof_us", None, low=0.0, high=1e6, low_open=True,
                                   allow_none=True),
            model_ar=rt.number("model_ar", None, low=1e-3, high=10.0, allow_none=True),
        ))
        rt.finish()
    t.finish()
    return tuple(rows)


def _measurement(t: Table | None, base_dir: Path | None) -> Path | None:
    if t is None:
        return None
    name = t.string("file", required=True)
    t.finish()
    path = Path(name)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    if not path.is_file():
        raise t.error("file", f"names '{path}', which does not exist")
    return path
