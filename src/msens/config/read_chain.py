"""Readers of a study's chain tables: beads, wall, damping, striker, inserts, precompression.

Each reader takes one :class:`msens.io.tomlreader.Table`, checks its keys (type, range,
plausibility, and the cross-checks that need several keys, such as the dashpot time and the
static contact load) and returns a spec of :mod:`msens.config.schema`.
"""

from __future__ import annotations

import math

from msens.chain.model import DampingLaw as Damping
from msens.config import plausible as P
from msens.config.schema import ChainSpec, InsertSpec, PrecompressionSpec, StrikerSpec, WallSpec
from msens.errors import shorten
from msens.io.tomlreader import Table
from msens.params.units import G0


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
        raise t.error(key, f"must be <= {limit:.3g} for beads of {mass:g} kg, got {gamma!r}: "
                           f"its dashpot would stop a bead in under "
                           f"{P.MIN_DASHPOT_TIME_S:g} s, faster than any bead contact "
                           "vibrates (the chain would carry no wave)")


def _striker(t: Table) -> StrikerSpec:
    has_h, has_v = t.has("drop_height_m"), t.has("velocity_m_per_s")
    if has_h == has_v:
        # a typo of one of them is named, not only the missing key
        unknown = [k for k in t.keys() if k not in ("drop_height_m", "velocity_m_per_s")]
        typo = f" (unknown key '{t.key(unknown[0])}' given)" if unknown else ""
        raise t.error("drop_height_m", f"or 'striker.velocity_m_per_s': give exactly one{typo}")
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
                                  f"2 <= first <= last <= {n - 1}, got {shorten(contacts)}")
    if contacts[0] == 1:  # +F on the striker, which is in flight: -F alone pulls the chain
        raise t.error("contacts", f"must start at contact 2 or later, got {contacts!r}: "
                                  "contact 1 is the striker's, which touches the chain only "
                                  "at impact and carries no static force")
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
                                        f"diameter) of its particle, got {offset!r} m: "
                                        "further, it sits nearer the next particle; name that "
                                        "particle instead")
    return offset
