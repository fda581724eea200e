"""The hidden-effect campaign's cases, and each effect's physics in the independent simulator.

Effect names and parameter names are msens's diagnose library's (so the truth can be scored
against its report); the plausible ranges are those its hidden-effect bench draws from;
the physics of each effect is implemented here, on :class:`~benchmarks.independent.sim.World`:

- ``striker_velocity``: the striker hits at nominal x (1 - u), u in [0.1, 0.3];
- ``wall_stiffness``: the wall's Young's modulus E_w log-uniform in [20, 120] GPa (its
  Hertz prefactor recomputed);
- ``wall_dissipation``: a linear-loading dashpot gamma_w in [1, 8] kg/s on the wall contact;
- ``magnetic_precompression``: an extra static compression F in [0.5, 3] N on the four
  contacts c_{p-2}..c_{p+1} around each coil (+F on particle p - 2, -F on particle p + 2);
- ``static_precompression``: F in [0.5, 3] N on a run of 2-5 contacts from c_3..c_24;
- ``contact_damping_law``: Hertz-Kuwabara-Kono dashpot gamma d^(1/2) d' on the bead contacts,
  gamma log-uniform in [1000, 4000] kg/(s m^0.5) (wall: 0, as the study's gamma_w);
- ``tube_friction``: drag -c v on every particle, c log-uniform in [0.05, 0.5] N s/m;
- ``daq_lowpass``: a first-order low-pass of time constant log-uniform in [0.5, 3] us as a
  state of the read-out;
- ``magnet_remanence``: all magnets x (1 +- u), u in [0.1, 0.4]: their pull and the coils'
  sensitivities from the remanence tables;
- ``coil_position``: one coil (random) moved by +-[0.5, 2] mm (+ toward the striker);
- ``cable_capacitance``: cable capacitance log-uniform in [0.3, 3] nF.

Outside the library (:data:`OUTSIDE`): things no library effect models.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from benchmarks.independent.field import FieldTables
from benchmarks.independent.sim import (
    Chain,
    StudyNumbers,
    World,
    hertz_prefactor,
    with_remanence,
)

#: Every library effect that applies to the main study's physics MsS (msens's
#: ``registry()`` with ``applies(ctx)``: sensor_position and sensor_mass do not).
EFFECTS = ("striker_velocity", "wall_stiffness", "wall_dissipation",
           "magnetic_precompression", "static_precompression", "contact_damping_law",
           "tube_friction", "daq_lowpass", "magnet_remanence", "coil_position",
           "cable_capacitance")

#: Effects outside the library.
OUTSIDE = {
    "brass_bead": "bead 6 is brass (8.5 g/cm^3, E = 100 GPa, nu = 0.34) of the same size",
    "soft_contact": "contact c_8 (a cracked bead) at 0.35 of its Hertz stiffness",
    "sensor_resonance": "a 250 kHz, Q = 6 resonance of the sensor amplifiers",
    "amplifier_saturation": "soft saturation of the amplifiers, v -> V tanh(v / V), V the peak",
    "double_striker": "a second striker bead falling with the first, 25 um behind it",
    "small_bead": "bead 22 is a 3.97 mm (5/32 in) bead of the same steel",
}

#: Shots per effect case, cycled (1-8 shots; the issue's time limit is per 8-shot file).
SHOTS = (1, 4, 8)
#: Shots of the null cases.
NULL_SHOTS = (1, 2, 3, 5, 8, 8)


@dataclass(frozen=True)
class Case:
    """One file of the campaign.

    Attributes
    ----------
    name : str
    kind : {"effect", "null", "outside"}
    effect : str
        Library effect name, ``none`` (null) or the outside effect's name.
    parameters : dict
        The truth, in the library's parameter names (SI).
    shots : int
    seed : int
    """

    name: str
    kind: str
    effect: str
    parameters: dict = field(default_factory=dict)
    shots: int = 1
    seed: int = 0


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def draw(effect: str, s: StudyNumbers, rng: np.random.Generator) -> dict:
    """A random plausible parameter set of ``effect``."""
    if effect == "striker_velocity":
        return {"striker_velocity_m_per_s": s.velocity * (1 - float(rng.uniform(0.1, 0.3)))}
    if effect == "wall_stiffness":
        return {"wall_youngs_modulus_pa": _log_uniform(rng, 20e9, 120e9)}
    if effect == "wall_dissipation":
        return {"gamma_wall_kg_per_s": float(rng.uniform(1.0, 8.0))}
    if effect == "magnetic_precompression":
        return {"precompression_force_n": float(rng.uniform(0.5, 3.0))}
    if effect == "static_precompression":
        return {"first_contact": int(rng.integers(3, 25)),
                "contact_count": int(rng.integers(2, 6)),
                "precompression_force_n": float(rng.uniform(0.5, 3.0))}
    if effect == "contact_damping_law":
        return {"gamma_hkk_kg_per_s_m05": _log_uniform(rng, 1000.0, 4000.0)}
    if effect == "tube_friction":
        return {"tube_drag_n_s_per_m": _log_uniform(rng, 0.05, 0.5)}
    if effect == "daq_lowpass":
        return {"lowpass_tau_s": _log_uniform(rng, 0.5e-6, 3e-6)}
    if effect == "magnet_remanence":
        return {"remanence_factor": 1.0 + float(rng.choice([-1.0, 1.0])
                                                * rng.uniform(0.1, 0.4))}
    if effect == "coil_position":
        offsets = {"coil_offset_m_top": 0.0, "coil_offset_m_bottom": 0.0}
        key = str(rng.choice(sorted(offsets)))
        offsets[key] = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.5e-3, 2e-3))
        return offsets
    if effect == "cable_capacitance":
        return {"cable_capacitance_f": _log_uniform(rng, 0.3e-9, 3e-9)}
    raise ValueError(f"unknown effect {effect!r}")


def _compress(static: np.ndarray, first: int, count: int, force: float) -> np.ndarray:
    """Static forces compressing contacts c_first..c_{first+count-1} (1-based) by
    ``force``: +F on particle ``first``, -F on particle ``first + count`` (1-based)."""
    out = np.array(static)
    out[first - 1] += force
    out[first + count - 1] -= force
    return out


def apply(world: World, effect: str, p: dict, s: StudyNumbers,
          tables: FieldTables) -> World:
    """The world with a library effect at parameters ``p``."""
    ch = world.chain
    if effect == "striker_velocity":
        vel = np.array(ch.velocity)
        vel[0] = p["striker_velocity_m_per_s"]
        return replace(world, chain=replace(ch, velocity=vel))
    if effect == "wall_stiffness":
        stiff = np.array(ch.stiffness)
        stiff[-1] = hertz_prefactor(s.youngs, s.poisson, s.radius,
                                    p["wall_youngs_modulus_pa"], s.wall_poisson, None)
        return replace(world, chain=replace(ch, stiffness=stiff))
    if effect == "wall_dissipation":
        damping = np.array(ch.damping)
        damping[-1] = p["gamma_wall_kg_per_s"]
        return replace(world, chain=replace(ch, damping=damping))
    if effect == "magnetic_precompression":
        static = ch.static
        for particle in s.particles:
            static = _compress(static, particle - 2, 4, p["precompression_force_n"])
        return replace(world, chain=replace(ch, static=static))
    if effect == "static_precompression":
        first, count = int(p["first_contact"]), int(p["contact_count"])
        static = _compress(ch.static, first, min(count, ch.n - first),
                           p["precompression_force_n"])
        return replace(world, chain=replace(ch, static=static))
    if effect == "contact_damping_law":
        damping = np.full(ch.n, p["gamma_hkk_kg_per_s_m05"])
        damping[-1] = 0.0
        return replace(world, chain=replace(ch, damping=damping, law="hkk"))
    if effect == "tube_friction":
        return replace(world, chain=replace(ch, drag=np.full(ch.n,
                                                             p["tube_drag_n_s_per_m"])))
    if effect == "daq_lowpass":
        return replace(world, electronics=replace(world.electronics,
                                                  lowpass_tau=p["lowpass_tau_s"]))
    if effect == "magnet_remanence":
        return with_remanence(world, tables, p["remanence_factor"])
    if effect == "coil_position":
        return replace(world, offsets=(p["coil_offset_m_top"], p["coil_offset_m_bottom"]))
    if effect == "cable_capacitance":
        return replace(world, electronics=replace(world.electronics,
                                                  cable_capacitance=p["cable_capacitance_f"]))
    raise ValueError(f"unknown effect {effect!r}")


def outside(world: World, name: str, s: StudyNumbers) -> World:
    """The world with an effect outside the library (:data:`OUTSIDE`)."""
    ch = world.chain
    mass, stiff = np.array(ch.mass), np.array(ch.stiffness)
    steel = (s.youngs, s.poisson, s.radius)
    if name == "brass_bead":
        k = 5  # bead 6 (0-based 5), between the striker and the top coil
        rho_steel = s.mass / (4 / 3 * np.pi * s.radius**3)
        mass[k] *= 8500.0 / rho_steel
        a = hertz_prefactor(*steel, 100e9, 0.34, s.radius)
        stiff[k - 1] = stiff[k] = a
    elif name == "soft_contact":
        stiff[7] *= 0.35
    elif name == "small_bead":
        k, rs = 21, 0.5 * 3.97e-3
        mass[k] *= (rs / s.radius) ** 3
        a = hertz_prefactor(*steel, s.youngs, s.poisson, rs)
        stiff[k - 1] = stiff[k] = a
    elif name == "sensor_resonance":
        return replace(world, electronics=replace(world.electronics, resonance_hz=250e3,
                                                  resonance_q=6.0))
    elif name == "amplifier_saturation":
        return replace(world, saturation=1.0)
    elif name == "double_striker":
        first = lambda a, v: np.concatenate([[v], a])  # noqa: E731
        gap = first(ch.gap, 0.0)
        gap[0] = 25e-6
        chain = Chain(mass=first(mass, s.mass), stiffness=first(stiff, stiff[0]),
                      damping=first(ch.damping, ch.damping[0]), law=ch.law,
                      static=first(ch.static, 0.0), drag=first(ch.drag, ch.drag[0]),
                      gap=gap, velocity=first(ch.velocity, ch.velocity[0]))
        return replace(world, chain=chain, shift=1)
    else:
        raise ValueError(f"unknown outside effect {name!r}")
    return replace(world, chain=replace(ch, mass=mass, stiffness=stiff))


def campaign(s: StudyNumbers, seed: int = 35, per_effect: int = 2,
             extra: tuple[str, ...] = ("static_precompression", "coil_position")
             ) -> list[Case]:
    """The campaign's cases: ``per_effect`` draws of every effect in :data:`EFFECTS` plus
    one more of each of ``extra`` (>= 24 effect cases), six null cases with 1-8 shots, and
    every outside effect; seeded by ``seed``."""
    rng = np.random.default_rng(seed)
    cases = []
    order = [e for _ in range(per_effect) for e in EFFECTS] + list(extra)
    for i, effect in enumerate(order):
        k = sum(1 for c in cases if c.effect == effect) + 1
        cases.append(Case(f"{effect}-{k}", "effect", effect, draw(effect, s, rng),
                          shots=SHOTS[i % len(SHOTS)], seed=seed * 1000 + i))
    for i, shots in enumerate(NULL_SHOTS):
        cases.append(Case(f"null-{i + 1}", "null", "none", {}, shots=shots,
                          seed=seed * 1000 + 100 + i))
    for i, name in enumerate(OUTSIDE):
        cases.append(Case(f"outside-{name}", "outside", name, {},
                          shots=SHOTS[i % len(SHOTS)], seed=seed * 1000 + 200 + i))
    return cases


def world_of(case: Case, s: StudyNumbers, tables: FieldTables, base: World) -> World:
    """The simulated rig of ``case``."""
    if case.kind == "effect":
        return apply(base, case.effect, case.parameters, s, tables)
    if case.kind == "outside":
        return outside(base, case.effect, s)
    return base
