"""Discrete particle chain (paper Eq. 6-9): contact laws, model, static equilibrium and the
compiled time integrator. Knows nothing of fields, sensors or studies."""

from msens.chain.equilibrium import static_contact_forces, static_equilibrium
from msens.chain.integrate import (
    ChainResult,
    contact_forces,
    initial_state,
    particle_accelerations,
    simulate,
    simulate_batch,
    simulate_reference,
    stable_step,
)
from msens.chain.model import Chain, DampingLaw, uniform_chain
from msens.chain.published import paper_chain, striker_velocity
from msens.mechanics.hertz import hertz_energy, hertz_sphere_flat, hertz_sphere_sphere

__all__ = [
    "Chain",
    "ChainResult",
    "DampingLaw",
    "contact_forces",
    "hertz_energy",
    "hertz_sphere_flat",
    "hertz_sphere_sphere",
    "initial_state",
    "paper_chain",
    "particle_accelerations",
    "simulate",
    "simulate_batch",
    "simulate_reference",
    "stable_step",
    "static_contact_forces",
    "static_equilibrium",
    "striker_velocity",
    "uniform_chain",
]
