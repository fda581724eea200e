"""The field model's tabulated outputs for the independent simulator, read once and perturbed.

What is read from msens (and nothing else of its field code path is used afterwards):

- per coil (particles 13 and 18) and contact c = 1..30: dLambda/dF_c (Villari, Wb/N) and
  dLambda/ddelta_c (contact approach, Wb/m), at the nominal position, on the tabulated grid
  of axial coil offsets (-3..3 mm) and at the remanence factors the field model was solved
  at (0.5..1.5);
- per coil and mapped contact: the contact map's shape as a table of the equivalent
  approach delta_eq(delta) on a dense grid of approaches (the nonlinear part of
  Lambda_c(delta), unit slope at the static contact);
- the magnets' static pull on each particle (N, + toward the wall), nominal and per
  remanence factor;
- each coil's R (Ohm), bias-point L (H) and winding capacitance (F).

Perturbation (:func:`perturbed`): every quantity is multiplied by (1 + s e), e standard
normal, drawn once per quantity and element from one seed (a second field solver: its
differences from the first are fixed, not redrawn per case), s = 1 % (the issue's measured
difference between two field solvers in the magnets' pull and the contact sensitivities).
The same factor multiplies a contact's sensitivity at every offset and remanence factor,
and the map's nonlinear part delta_eq - delta is scaled by its own factor.

The simulator interpolates these tables itself (PCHIP in offset and remanence, linear in
approach), not with msens's splines.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

#: Relative std of the field model's error (issue 35: two independent solvers differ by
#: ~1 % in the magnets' pull and the contact sensitivities).
FIELD_ACCURACY = 0.01
#: Seed of the perturbation (one fixed "second field solver").
FIELD_SEED = 20261128

#: Approach grid of the contact-map tables, m: dense near the static contact.
DELTA_GRID = np.unique(np.concatenate([np.linspace(-30e-6, -2e-6, 281),
                                       np.linspace(-2e-6, 6e-6, 1601)]))


@dataclass(frozen=True)
class CoilTables:
    """Tabulated outputs of one coil (arrays over the 30 contacts c = 1..30).

    Attributes
    ----------
    particle : int
    villari, approach : ndarray, shape (30,)
        dLambda/dF_c (Wb/N) and dLambda/ddelta_c (Wb/m), nominal position and remanence.
    offsets : ndarray, shape (n_o,)
        Coil offsets of the tables, m (+ toward the striker).
    villari_by_offset, approach_by_offset : ndarray, shape (n_o, 30)
    remanence : ndarray, shape (n_r,)
        Remanence factors of the tables.
    villari_by_remanence, approach_by_remanence : ndarray, shape (n_r, 30)
    mapped : ndarray of int, shape (n_m,)
        Contacts with a nonlinear contact map.
    delta_eq : ndarray, shape (n_m, n_d)
        Equivalent approach of each mapped contact on :data:`DELTA_GRID`, m.
    resistance, inductance, winding_capacitance : float
        Ohm, H, F.
    """

    particle: int
    villari: np.ndarray
    approach: np.ndarray
    offsets: np.ndarray
    villari_by_offset: np.ndarray
    approach_by_offset: np.ndarray
    remanence: np.ndarray
    villari_by_remanence: np.ndarray
    approach_by_remanence: np.ndarray
    mapped: np.ndarray
    delta_eq: np.ndarray
    resistance: float
    inductance: float
    winding_capacitance: float


@dataclass(frozen=True)
class FieldTables:
    """The field model's outputs for the main study's setup.

    Attributes
    ----------
    coils : tuple of CoilTables
        In the order of the setup's sensors (top coil first).
    pull : ndarray, shape (30,)
        Magnets' static pull on each particle, N (+ toward the wall).
    remanence : ndarray, shape (n_r,)
    pull_by_remanence : ndarray, shape (n_r, 30)
    """

    coils: tuple[CoilTables, ...]
    pull: np.ndarray
    remanence: np.ndarray
    pull_by_remanence: np.ndarray


def main_study():
    """The study this simulator implements: the main study's magnetostatic variant
    (``[field] eddy_currents = false``; the simulator has no eddy currents in the steel, so
    msens is compared with, and diagnoses its data with, the same physics)."""
    from msens import api

    return api.load_default(eddy_currents=False)


def read_tables(study) -> FieldTables:
    """Read the tabulated outputs of msens's field model for ``study``'s first setup (its
    transducer objects, the contact maps, the remanence family): the one contact with
    msens's field code."""
    from msens.diagnose.effects import Context
    from msens.diagnose.physics import setup_physics
    from msens.readout.coil import winding_capacitance

    ctx = Context(study, study.setups[0])
    physics = [p for p in setup_physics(ctx) if p is not None]
    model = physics[0].model
    family = model.family()
    nodes = np.asarray(family.nodes, dtype=float)
    coils = []
    for spec in physics:
        tr = model.transducers[spec.particle]
        contacts = np.asarray(tr.contacts)
        grid = np.repeat(DELTA_GRID[:, None], contacts.size, axis=1)
        eq = tr.equivalent_approach(grid)  # the maps' shapes, tabulated
        mapped = np.asarray(tr.approach_map.contacts if tr.approach_map else (), dtype=int)
        cols = np.searchsorted(contacts, mapped)
        members = [family.transducer(spec.particle, float(x)) for x in nodes]
        coils.append(CoilTables(
            particle=spec.particle, villari=np.array(tr.sensitivity_villari),
            approach=np.array(tr.dlambda_dapproach), offsets=np.array(tr.offsets),
            villari_by_offset=np.array(tr.villari_by_offset),
            approach_by_offset=np.array(tr.approach_by_offset), remanence=nodes,
            villari_by_remanence=np.array([m.sensitivity_villari for m in members]),
            approach_by_remanence=np.array([m.dlambda_dapproach for m in members]),
            mapped=mapped, delta_eq=np.array(eq[:, cols].T),
            resistance=float(tr.resistance_ohm), inductance=float(tr.inductance_H),
            winding_capacitance=float(winding_capacitance(spec.coil))))
    from msens.magnetics.transducer import magnetic_precompression

    return FieldTables(coils=tuple(coils),
                       pull=np.array(magnetic_precompression(model.transducers)),
                       remanence=nodes,
                       pull_by_remanence=np.array([family.particle_force(float(x))
                                                   for x in nodes]))


def perturbed(tables: FieldTables, accuracy: float = FIELD_ACCURACY,
              seed: int = FIELD_SEED) -> FieldTables:
    """The tables as a second field solver would give them: each quantity and element times
    (1 + accuracy e), e standard normal, one draw per element for all offsets and remanence
    factors (see the module docstring). ``accuracy = 0`` returns the tables unchanged."""
    if accuracy == 0.0:
        return tables
    rng = np.random.default_rng(seed)

    def factor(shape) -> np.ndarray:
        return 1.0 + accuracy * rng.standard_normal(shape)

    coils = []
    for c in tables.coils:
        fv, fa = factor(c.villari.shape), factor(c.approach.shape)
        fm = factor((c.mapped.size, 1))
        eq = DELTA_GRID[None, :] + fm * (c.delta_eq - DELTA_GRID[None, :])
        fr, fl, fc = factor(3)
        coils.append(replace(
            c, villari=c.villari * fv, approach=c.approach * fa,
            villari_by_offset=c.villari_by_offset * fv,
            approach_by_offset=c.approach_by_offset * fa,
            villari_by_remanence=c.villari_by_remanence * fv,
            approach_by_remanence=c.approach_by_remanence * fa, delta_eq=eq,
            resistance=c.resistance * fr, inductance=c.inductance * fl,
            winding_capacitance=c.winding_capacitance * fc))
    fp = factor(tables.pull.shape)
    return replace(tables, coils=tuple(coils), pull=tables.pull * fp,
                   pull_by_remanence=tables.pull_by_remanence * fp[None, :])
