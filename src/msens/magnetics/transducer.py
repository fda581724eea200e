"""Physics MsS transducer: each coil's flux linkage per unit of every contact's state.

:func:`compute_transducers` runs the field model of a
:class:`~msens.field.geometry.SensorGeometry` (cached mesh, nonlinear bias solve), builds the
incremental potentials of both mechanisms' sources (:func:`mechanism_potentials`: the Villari
magnetisation of every bead per newton, and the contact approach of every contact per metre)
with one factorisation, and reads each coil's flux linkage of them by exact quadrature over
its winding (:mod:`msens.magnetics.potentials`). Design sweeps read the same potentials
through a summed-area table (:mod:`msens.design.coil_sweep`), so a design and ``msens run``
share one implementation. Results are cached on disk as JSON keyed by a content hash.

Mechanisms (one name each, everywhere): ``"villari"`` (stress-induced magnetisation of the
beads, :mod:`msens.magnetics.villari`) and ``"approach"`` (the contact approach: the beads
move closer and the saturated contact necks grow, :mod:`msens.magnetics.approach`).

Sign conventions
----------------
* Λ is the coil's flux linkage for its current positive along +φ (B_z > 0 inside the coil);
  the open-circuit EMF is V = -dΛ/dt (:func:`emf`).
* Contact c (1-based, the paper's numbering) joins particles c and c + 1; contact N (the last
  particle) is the wall. Contact forces are compressive positive; the approach δ_c is the
  Hertz approach of the contact's force.
* ``magnetic_particle_force`` is indexed by particle - 1 (index 0 the striker), positive
  toward the wall (-z in the field model, +x in :mod:`msens.chain`).
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

from msens.errors import InputError, internal, require
from msens.field.build import MeshOptions
from msens.field.cache import committed_mesh_dirs, default_mesh_dir, geometry_key
from msens.field.geometry import Coil, SensorGeometry
from msens.field.sensor_model import (
    bias_problem,
    coil_resistance,
    contact_forces,
    group_force,
    load_mesh,
)
from msens.field.solve import FieldSolution, solve
from msens.io._files import atomic_write_bytes
from msens.io.hashing import canonical as _canonical
from msens.io.hashing import content_hash
from msens.magnetics.approach import approach_residuals, hertz_approach_rate, hertz_stiffness
from msens.magnetics.magnetoelastic import JilesAthertonSablik
from msens.magnetics.potentials import (
    TangentOperator,
    adjoint_linkage,
    linkage_table,
    rect_integral,
    region_linkage,
)
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.villari import (
    StressSampler,
    bead_state,
    bead_stress,
    coil_flux_linkage,
    contact_sensitivity,
    villari_sources,
)
from msens.mechanics.hertz import hertz_approach
from msens.params.materials import BEAD_STEEL, ElasticMaterial

_log = logging.getLogger(__name__)

#: Version of what :func:`transducers_for` computes; part of the cache key.
TRANSDUCER_VERSION = "transducer/3"
#: Coil offsets tabulated per transducer: ±OFFSET_SPAN in steps of OFFSET_STEP, m.
OFFSET_SPAN = 3e-3
OFFSET_STEP = 0.1e-3

Mechanism = Literal["villari", "approach", "both"]
MECHANISMS: tuple[str, ...] = ("villari", "approach", "both")


@dataclass(frozen=True)
class Transducer:
    """Linear model of one physics MsS: flux linkage per unit of each contact's state.

    Attributes
    ----------
    particle : int
        Particle at the coil's centre (paper numbering).
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers covered (contact c joins particles c and c + 1).
    sensitivity_villari : ndarray, shape (n_c,)
        ∂Λ/∂F_c of the Villari effect, Wb/N.
    dlambda_dapproach : ndarray, shape (n_c,)
        ∂Λ/∂δ_c of the contact approach, Wb/m.
    contact_stiffness : float
        Hertz prefactor A (F = A δ^{3/2}), N/m^1.5: δ_c(t) = ([F_c]_+/A)^{2/3}.
    reference_force : float
        Static load at which the bead stress (Villari) and the linearised approach
        sensitivity are evaluated, N.
    magnetic_particle_force : ndarray, shape (n_particles,)
        Static magnetic force on each particle (index particle - 1), N, positive toward the
        wall. Whole-model force (all magnets of the geometry).
    resistance_ohm : float
        DC coil resistance at 20 °C, Ohm.
    inductance_H : float
        Incremental coil inductance at the bias point, H.
    turns : int
    source : str
        Where the numbers come from (model, cache key).
    offsets : ndarray, shape (n_o,), optional
        Axial coil offsets from its position, m (uniform, symmetric about 0).
    villari_by_offset, approach_by_offset : ndarray, shape (n_o, n_c), optional
        ``sensitivity_villari`` and ``dlambda_dapproach`` of the same coil moved by each
        offset (magnets and beads fixed), from the same source potentials
        (:func:`offset_profiles`); :meth:`shifted` interpolates them.
    """

    particle: int
    contacts: np.ndarray
    sensitivity_villari: np.ndarray
    dlambda_dapproach: np.ndarray
    contact_stiffness: float
    reference_force: float
    magnetic_particle_force: np.ndarray
    resistance_ohm: float
    inductance_H: float
    turns: int
    source: str
    offsets: np.ndarray | None = None
    villari_by_offset: np.ndarray | None = None
    approach_by_offset: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = np.asarray(self.contacts).shape
        require(np.asarray(self.sensitivity_villari).shape == n
                and np.asarray(self.dlambda_dapproach).shape == n,
                "internal: Transducer sensitivities must have one value per contact")

    @property
    def sensitivity_approach(self) -> np.ndarray:
        """∂Λ/∂F_c of the contact approach linearised at ``reference_force``, Wb/N."""
        rate = 2.0 / 3.0 * float(hertz_approach(self.reference_force, self.contact_stiffness)) \
            / self.reference_force
        return np.asarray(self.dlambda_dapproach) * rate

    def shifted(self, offset: float) -> Transducer:
        """The same coil moved axially by ``offset`` (m, + toward the striker), magnets and
        beads fixed: sensitivities by cubic interpolation of the offset profiles. R and L are
        kept (the coil's inductance changes little over a few mm)."""
        internal(self.offsets is not None, "internal: transducer has no offset profiles")
        require(self.offsets[0] <= offset <= self.offsets[-1],
                f"coil offset {offset} m outside the tabulated "
                f"{self.offsets[0]:g}..{self.offsets[-1]:g} m")
        from scipy.interpolate import CubicSpline

        vil = CubicSpline(self.offsets, self.villari_by_offset, axis=0)(offset)
        app = CubicSpline(self.offsets, self.approach_by_offset, axis=0)(offset)
        return replace(self, sensitivity_villari=np.asarray(vil),
                       dlambda_dapproach=np.asarray(app))

    def sensitivity(self, mechanism: Mechanism = "both") -> np.ndarray:
        """∂Λ/∂F_c of the chosen mechanism(s) at the reference load, Wb/N, shape (n_c,)."""
        _check_mechanism(mechanism)
        if mechanism == "villari":
            return np.asarray(self.sensitivity_villari)
        if mechanism == "approach":
            return self.sensitivity_approach
        return np.asarray(self.sensitivity_villari) + self.sensitivity_approach


def _check_mechanism(mechanism: str) -> None:
    require(mechanism in MECHANISMS,
            f"mechanism must be one of {', '.join(MECHANISMS)}, got {mechanism!r}")


# ----------------------------------------------------------------------------- signal

@dataclass(frozen=True)
class ContactRates:
    """Rates of the contacts a transducer reads, for one chain history.

    Attributes
    ----------
    t : ndarray, shape (nt,)
        s.
    force : ndarray, shape (nt, n_c)
        dF_c/dt, N/s (zero for contacts beyond the chain's columns).
    approach : ndarray, shape (nt, n_c)
        dδ_c/dt of the Hertz approach δ_c = ([F_c]_+/A)^{2/3}, m/s.
    """

    t: np.ndarray
    force: np.ndarray
    approach: np.ndarray


def contact_forces_of(force: np.ndarray, contacts: np.ndarray,
                      columns: np.ndarray | None = None) -> np.ndarray:
    """The columns of ``contacts`` from a chain's contact forces, zeros where absent.

    Parameters
    ----------
    force : ndarray, shape (nt, m)
        Contact forces, N.
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers wanted.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force`` (sorted); default column k is contact
        k + 1 (as in :mod:`msens.chain`).

    Returns
    -------
    ndarray, shape (nt, n_c)
    """
    f = np.asarray(force, dtype=float)
    contacts = np.asarray(contacts, dtype=int)
    if columns is None:
        columns = np.arange(1, f.shape[1] + 1)
    columns = np.asarray(columns, dtype=int)
    k = np.clip(np.searchsorted(columns, contacts), 0, max(columns.size - 1, 0))
    use = (columns.size > 0) & (columns[k] == contacts)
    out = np.zeros((f.shape[0], contacts.size))
    out[:, use] = f[:, k[use]]
    return out


def contact_rates(t: np.ndarray, force: np.ndarray, contacts: np.ndarray,
                  stiffness: float, columns: np.ndarray | None = None,
                  approach: np.ndarray | None = None) -> ContactRates:
    """Force and approach rates of ``contacts`` from a chain's contact states.

    Parameters
    ----------
    t : ndarray, shape (nt,)
        Strictly increasing times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers.
    stiffness : float
        Hertz prefactor A, N/m^1.5.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force`` (see :func:`contact_forces_of`).
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches δ_c(t), m (negative: open), same columns as
        ``force``. Without it δ_c = ([F_c]_+/A)^{2/3}, whose slope in F is infinite at
        F = 0: a contact that unloads or opens between two samples then gives a spike.

    Notes
    -----
    Rates are :func:`numpy.gradient` (second order, also on non-uniform times).
    """
    t = np.asarray(t, dtype=float)
    require(t.ndim == 1 and t.size >= 2, "t must be 1-D with at least 2 samples")
    require(bool(np.all(np.diff(t) > 0)), "t must be strictly increasing")
    require(np.ndim(force) == 2 and np.shape(force)[0] == t.size,
            f"force must have shape (nt={t.size}, n_contacts), got "
            f"{np.shape(force)}")
    fc = contact_forces_of(force, contacts, columns)
    delta = hertz_approach(fc, stiffness) if approach is None else \
        contact_forces_of(approach, contacts, columns)
    return ContactRates(t=t, force=np.gradient(fc, t, axis=0),
                        approach=np.gradient(delta, t, axis=0))


def emf_from_rates(rates: ContactRates, sensitivity_villari: np.ndarray,
                   dlambda_dapproach: np.ndarray, mechanism: Mechanism = "both"
                   ) -> np.ndarray:
    """Open-circuit EMF V = -Σ_c [(∂Λ/∂F_c) dF_c/dt + (∂Λ/∂δ_c) dδ_c/dt], V.

    Parameters
    ----------
    rates : ContactRates
    sensitivity_villari, dlambda_dapproach : ndarray, shape (..., n_c)
        Wb/N and Wb/m; leading axes (e.g. coil designs) broadcast.
    mechanism : {"villari", "approach", "both"}

    Returns
    -------
    ndarray, shape (..., nt)
    """
    _check_mechanism(mechanism)
    out = 0.0
    if mechanism in ("villari", "both"):
        out = out - np.asarray(sensitivity_villari) @ rates.force.T
    if mechanism in ("approach", "both"):
        out = out - np.asarray(dlambda_dapproach) @ rates.approach.T
    return out


def rigid_translation_emf(transducer: Transducer, rates: ContactRates) -> np.ndarray:
    """The part of the contact-approach EMF that is the beads' rigid translation, V.

    Each approach source moves every modelled bead above its contact rigidly, so summed over
    contacts the sources move bead p by u_p = Σ_{c ≥ p} δ_c (the wall does not move): the
    beads' translation in the coil's and magnet's field gradients is contained in the
    contact-approach EMF. Its size is the sensitivity to translating all modelled beads
    together, T = ∂Λ/∂δ of the lowest modelled contact (no contact changes then), times the
    speed of the coil's bead: -T du_p/dt. Beads near the coil move together to within a few
    contact approaches, so this estimates the translation part of the signal.

    Parameters
    ----------
    transducer : Transducer
    rates : ContactRates
        Rates of ``transducer.contacts`` (:func:`contact_rates`).

    Returns
    -------
    ndarray, shape (nt,)
    """
    contacts = np.asarray(transducer.contacts)
    below = contacts >= transducer.particle
    speed = np.sum(rates.approach[:, below], axis=1)
    return -float(transducer.dlambda_dapproach[-1]) * speed


def open_contact_emf(transducer: Transducer, rates: ContactRates,
                     approach: np.ndarray) -> np.ndarray:
    """The part of the contact-approach EMF from contacts while they are open (δ_c < 0), V.

    The approach sources are linearised about the static load; for an open gap they are
    extrapolated linearly (a gap changes the field mesh's topology). This is how much of the
    signal rests on that extrapolation.

    Parameters
    ----------
    transducer : Transducer
    rates : ContactRates
        Rates of ``transducer.contacts``.
    approach : ndarray, shape (nt, n_c)
        δ_c(t) of the same contacts, m.

    Returns
    -------
    ndarray, shape (nt,)
    """
    parts = -rates.approach * np.asarray(transducer.dlambda_dapproach)[None, :]
    return np.where(np.asarray(approach) < 0.0, parts, 0.0).sum(axis=1)


def emf(transducer: Transducer, t: np.ndarray, force: np.ndarray,
        mechanism: Mechanism = "both", approach: np.ndarray | None = None) -> np.ndarray:
    """Open-circuit coil EMF of one transducer for a chain's contact forces, V.

    Parameters
    ----------
    transducer : Transducer
    t : ndarray, shape (nt,)
        s.
    force : ndarray, shape (nt, m)
        Contact forces, N (column k is contact k + 1).
    mechanism : {"villari", "approach", "both"}
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches, m (see :func:`contact_rates`).

    Returns
    -------
    ndarray, shape (nt,)
    """
    rates = contact_rates(t, force, transducer.contacts, transducer.contact_stiffness,
                          approach=approach)
    return emf_from_rates(rates, transducer.sensitivity_villari, transducer.dlambda_dapproach,
                          mechanism)


def magnetic_precompression(transducers: Mapping[int, Transducer] | list[Transducer]
                            ) -> np.ndarray:
    """Static magnetic force on each particle for the chain, N, + toward the wall.

    Transducers from the same field model (same ``source``) carry the same whole-model force
    and count once; those from different models are added (independent magnets).

    Returns
    -------
    ndarray, shape (n_particles,)
    """
    items = list(transducers.values()) if isinstance(transducers, Mapping) else list(transducers)
    require(len(items) > 0, "magnetic_precompression: no transducers given")
    seen: dict[str, np.ndarray] = {}
    for tr in items:
        seen.setdefault(tr.source, np.asarray(tr.magnetic_particle_force, dtype=float))
    sizes = {v.size for v in seen.values()}
    require(len(sizes) == 1, f"transducers describe chains of different lengths {sorted(sizes)}")
    return np.sum(list(seen.values()), axis=0)


# ----------------------------------------------------------------------------- computation

def particle_forces(sol: FieldSolution, geometry: SensorGeometry) -> np.ndarray:
    """Static magnetic force on every particle, N, + toward the wall, shape (count,).

    From the eggshell contact compressions C_c of :func:`contact_forces` (minus the force on
    all modelled beads above contact c): the force on bead p is C_p - C_{p-1}; the last
    modelled bead's lower compression is minus the force on all modelled beads.
    """
    b = geometry.beads
    comp = {c.upper: c.magnetic_force_N for c in contact_forces(sol, geometry)}
    comp[b.last] = -group_force(sol, [f"bead_{p}" for p in b.particles])
    out = np.zeros(b.count)
    for p in b.particles:
        out[p - 1] = comp[p] - comp.get(p - 1, 0.0)
    return out


@dataclass(frozen=True)
class MechanismPotentials:
    """Incremental potentials of every mechanism source at one bias point.

    Attributes
    ----------
    solution : FieldSolution
        The bias solution (mesh, basis).
    particles : ndarray of int, shape (n_b,)
        Beads with a Villari source, top to bottom (consecutive).
    contacts : ndarray of int, shape (n_a,)
        Contacts with an approach source (all beads above c move; empty when the approach
        mechanism is off).
    potentials : ndarray, shape (n_b + n_a, n_dofs)
        A_φ per newton of symmetric load on each bead (T m/N), then per metre of approach
        of each contact (T).
    count : int
        Particles in the chain.
    operator : TangentOperator
    villari_sources : list of (elements, mu0_dM)
        The Villari sources (for the adjoint check).
    approach_rhs : ndarray, shape (n_a, n_dofs)
        -∂R/∂δ_c (for the adjoint check).
    rhs : ndarray, shape (n_b + n_a, n_dofs), optional
        The load vectors f_s of all sources, in the order of ``potentials`` (K_t a_s = f_s;
        the eddy-current model :mod:`msens.magnetics.dynamic` solves the same sources with
        K_t + jωM_σ).
    """

    solution: FieldSolution
    particles: np.ndarray
    contacts: np.ndarray
    potentials: np.ndarray
    count: int
    operator: TangentOperator
    villari_sources: list
    approach_rhs: np.ndarray
    rhs: np.ndarray | None = None

    def contact_profiles(self, linkage: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                             np.ndarray]:
        """:func:`contact_profiles` of this model's sources."""
        return contact_profiles(self.particles, self.contacts, self.count, linkage)


def contact_profiles(particles: np.ndarray, approach_contacts: np.ndarray, count: int,
                     linkage: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-contact sensitivities from the sources' flux linkages with some coil(s).

    Parameters
    ----------
    particles : ndarray of int, shape (n_b,)
        Beads with a Villari source (consecutive).
    approach_contacts : ndarray of int, shape (n_a,)
        Contacts with an approach source.
    count : int
        Particles in the chain.
    linkage : ndarray, shape (..., n_b + n_a)
        Flux linkage of each source's potential with the coil(s), Wb per unit: Villari
        sources first, then approach sources.

    Returns
    -------
    contacts : ndarray of int, shape (n_b + 1,)
    sensitivity_villari : ndarray, shape (..., n_b + 1)
        ∂Λ/∂F_c, Wb/N.
    dlambda_dapproach : ndarray, shape (..., n_b + 1)
        ∂Λ/∂δ_c, Wb/m (zero where no approach source).
    """
    nb = np.asarray(particles).size
    contacts, s_vil = contact_sensitivity(particles, linkage[..., :nb], count)
    dl = np.zeros_like(s_vil)
    dl[..., np.searchsorted(contacts, approach_contacts)] = linkage[..., nb:]
    return contacts, s_vil, dl


def mechanism_potentials(sol: FieldSolution, geometry: SensorGeometry, *,
                         stress_force: float, law: JilesAthertonSablik,
                         material: ElasticMaterial = BEAD_STEEL, approach: bool = True,
                         timings: dict | None = None) -> MechanismPotentials:
    """Villari and contact-approach sources of every modelled bead and contact, solved.

    Parameters
    ----------
    sol : FieldSolution
        Bias solution of ``geometry``.
    geometry : SensorGeometry
    stress_force : float
        Force at which the bead stress is solved, N.
    law : JilesAthertonSablik
        Magnetoelastic law of the bead steel.
    material : ElasticMaterial
        Bead elasticity.
    approach : bool
        Include the contact-approach sources.
    timings : dict, optional
        Filled with the seconds each stage took.
    """
    timings = {} if timings is None else timings
    b = geometry.beads
    t0 = time.perf_counter()
    sampler = StressSampler(bead_stress(geometry, stress_force, material))
    operator = TangentOperator(sol)
    particles = np.array(list(b.particles))
    sources = villari_sources(sol, geometry, particles, sampler, law)
    timings["stress_and_tangent"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    if approach:
        res = approach_residuals(sol, geometry, list(b.particles))
        contacts = np.array(sorted(res))
        a_rhs = -np.array([res[int(c)] for c in contacts])
    else:
        contacts = np.zeros(0, dtype=int)
        a_rhs = np.zeros((0, sol.basis.N))
    timings["approach_residuals"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rhs = np.vstack([*(operator.magnetisation_rhs(el, m) for el, m in sources), a_rhs])
    pots = operator.solve(rhs)
    timings["source_solves"] = time.perf_counter() - t0
    return MechanismPotentials(solution=sol, particles=particles, contacts=contacts,
                               potentials=pots, count=b.count, operator=operator,
                               villari_sources=sources, approach_rhs=a_rhs, rhs=rhs)


def coil_linkage(model: MechanismPotentials, coil: Coil) -> np.ndarray:
    """Flux linkage of every source with a coil of the mesh (exact quadrature), shape (n_s,)."""
    return region_linkage(model.solution, model.potentials, f"coil_{coil.particle}",
                          coil.turns, coil.area)


def offset_profiles(model: MechanismPotentials, geometry: SensorGeometry, coil: Coil
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-contact sensitivities of a coil moved axially over ±OFFSET_SPAN.

    A summed-area table of the source potentials over the coil's radial span (the coil is
    air, so the potentials do not change when it moves) integrated over the moved winding.

    Returns
    -------
    offsets : ndarray, shape (n_o,)
        m.
    villari, approach : ndarray, shape (n_o, n_c)
        ∂Λ/∂F_c (Wb/N) and ∂Λ/∂δ_c (Wb/m) at each offset.
    """
    rect = geometry.coil_rect(next(u for u in geometry.sensors
                                   if u.coil.particle == coil.particle))
    n = round(OFFSET_SPAN / OFFSET_STEP)
    offsets = np.arange(-n, n + 1) * OFFSET_STEP
    pad = 2 * OFFSET_STEP
    table = linkage_table(model.solution, model.potentials, (rect.r0, rect.r1),
                          (rect.z0 - OFFSET_SPAN - pad, rect.z1 + OFFSET_SPAN + pad),
                          spacing=OFFSET_STEP / 2)
    ones = np.ones(offsets.size)
    link = coil.turns / coil.area * rect_integral(table, rect.r0 * ones, rect.r1 * ones,
                                                  rect.z0 + offsets, rect.z1 + offsets)
    _, vil, app = model.contact_profiles(link)
    return offsets, vil, app


def adjoint_check(model: MechanismPotentials, coil: Coil, linkage: np.ndarray
                  ) -> tuple[float, float]:
    """The coil's own incremental field against the source potentials (reciprocity).

    Returns
    -------
    inductance : float
        Incremental inductance of the coil at the bias point, H.
    error : float
        max |Λ_s(adjoint) - Λ_s(potentials)| / max |Λ_s| over all sources.
    """
    sol = model.solution
    state = bead_state(sol, coil)
    w = sol.disc.quad.w
    vil = [adjoint_linkage(state.h_coil, el, m, w) for el, m in model.villari_sources]
    app = [2 * math.pi * float(state.incremental.a @ r) for r in model.approach_rhs]
    adj = np.array(vil + app)
    scale = float(np.max(np.abs(linkage))) or 1.0
    inductance = coil_flux_linkage(sol, state.incremental.a, coil)
    return inductance, float(np.max(np.abs(adj - linkage))) / scale


@dataclass(frozen=True)
class TransducerReport:
    """Everything :func:`compute_transducers` finds (also what the cache stores).

    Attributes
    ----------
    transducers : dict of int -> Transducer
    details : dict
        JSON-ready diagnostics: per coil the bead Villari sensitivities, the reciprocity
        check; timings; mesh size.
    """

    transducers: dict[int, Transducer]
    details: dict


def bias_solution(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                  mesh_dir: str | Path | None = None, max_iter: int = 40
                  ) -> tuple[FieldSolution, Path]:
    """Mesh (cached) and nonlinear bias solve of a geometry."""
    axi, path = load_mesh(geometry, options, mesh_dir)
    return solve(bias_problem(geometry, axi), max_iter=max_iter), path


def compute_transducers(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                        mesh_dir: str | Path | None = None, stress_force: float | None = None,
                        law: JilesAthertonSablik | None = None,
                        material: ElasticMaterial = BEAD_STEEL, approach: bool = True,
                        max_iter: int = 40) -> TransducerReport:
    """Run the field model and build a :class:`Transducer` for every coil (no cache).

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    mesh_dir : str or Path, optional
        Mesh cache directory.
    stress_force : float, optional
        Force at which the bead stress is solved (the secant sensitivity's force), N; default
        the geometry's ``contact_load`` (the static load that sets the model's flats).
    law : JilesAthertonSablik, optional
        Magnetoelastic law of the beads; default :func:`msens.magnetics.steel_law.law_for_steel` of
        the geometry's B–H table.
    material : ElasticMaterial
        Bead elasticity.
    approach : bool
        Compute the contact-approach mechanism; zeros otherwise.
    max_iter : int
        Newton iterations allowed in the bias solve.
    """
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    require(math.isfinite(force) and force > 0, f"stress_force must be > 0 N, got {force}")
    law = law_for_steel(geometry.steel) if law is None else law
    timings: dict[str, float] = {}
    _log.info("transducers: field mesh and nonlinear bias solve")
    t0 = time.perf_counter()
    sol, path = bias_solution(geometry, options=options, mesh_dir=mesh_dir, max_iter=max_iter)
    timings["mesh_and_bias_solve"] = time.perf_counter() - t0
    _log.info("transducers: bead stress, Villari and contact-approach sources, their "
              "potentials (%d dofs)", sol.dofs)
    model = mechanism_potentials(sol, geometry, stress_force=force, law=law,
                                 material=material, approach=approach, timings=timings)
    t0 = time.perf_counter()
    pforce = particle_forces(sol, geometry)
    timings["magnetic_forces"] = time.perf_counter() - t0

    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    approach=approach)
    src = (f"msens.magnetics {TRANSDUCER_VERSION}: Villari (JAS law, stress at {force:.4g} N)"
           f" + contact approach, source potentials; field mesh {path.name}; key {key}")
    stiffness = hertz_stiffness(geometry.beads.radius, material)
    out: dict[int, Transducer] = {}
    details: dict = {"key": key, "mesh": path.name, "elements": sol.problem.mesh.n_elements,
                     "dofs": sol.dofs, "newton_iterations": sol.iterations,
                     "stress_force_N": force,
                     "approach_rate_m_per_N": hertz_approach_rate(
                         force, geometry.beads.radius, material), "coils": {}}
    for unit in geometry.iter_units():
        coil = unit.coil
        t0 = time.perf_counter()
        link = coil_linkage(model, coil)
        contacts, s_vil, dl = model.contact_profiles(link)
        inductance, err = adjoint_check(model, coil, link)
        offsets, vil_o, app_o = offset_profiles(model, geometry, coil)
        timings[f"coil_{coil.particle}"] = time.perf_counter() - t0
        out[coil.particle] = Transducer(
            particle=coil.particle, contacts=contacts, sensitivity_villari=s_vil,
            dlambda_dapproach=dl, contact_stiffness=stiffness, reference_force=force,
            magnetic_particle_force=pforce, resistance_ohm=coil_resistance(coil),
            inductance_H=inductance, turns=coil.turns, source=src, offsets=offsets,
            villari_by_offset=vil_o, approach_by_offset=app_o)
        details["coils"][str(coil.particle)] = {
            "particles": model.particles.tolist(),
            "bead_sensitivity_Wb_per_N": link[:model.particles.size].tolist(),
            "reciprocity_adjoint_rel_error": err}
    details["timings_s"] = timings
    _log.info("transducers: computed in %.1f s (%s)", sum(timings.values()),
              ", ".join(f"{k} {v:.1f} s" for k, v in timings.items()))
    return TransducerReport(out, details)


def cache_key(geometry: SensorGeometry, options: MeshOptions | None = None, *,
              stress_force: float, law: JilesAthertonSablik, material: ElasticMaterial,
              approach: bool) -> str:
    """Content hash (16 hex digits) of everything a transducer set depends on.

    The mesh key leaves out the materials (the steel's B–H curve, the magnets' grade,
    remanence and recoil permeability); they enter here.
    """
    magnets = [None if u.magnet is None else
               [u.magnet.grade, repr(float(u.magnet.remanence)),
                repr(float(u.magnet.recoil_permeability))] for u in geometry.sensors]
    payload = {"version": TRANSDUCER_VERSION, "mesh": geometry_key(geometry, options),
               "stress_force": repr(float(stress_force)), "law": _canonical(law),
               "material": _canonical(material), "approach": bool(approach),
               "magnets": magnets}
    if not geometry.default_steel:
        payload["steel_bh"] = {"b": _canonical(geometry.steel.b),
                               "h": _canonical(geometry.steel.h)}
    if geometry.reversibility != 1.0:
        payload["reversibility"] = repr(float(geometry.reversibility))
    return content_hash(payload, 16)


def _to_json(report: TransducerReport) -> dict:
    trs = {}
    for p, tr in report.transducers.items():
        trs[str(p)] = {
            "particle": tr.particle, "contacts": np.asarray(tr.contacts).tolist(),
            "sensitivity_villari_Wb_per_N": np.asarray(tr.sensitivity_villari).tolist(),
            "dLambda_dapproach_Wb_per_m": np.asarray(tr.dlambda_dapproach).tolist(),
            "contact_stiffness_N_per_m1.5": tr.contact_stiffness,
            "reference_force_N": tr.reference_force,
            "magnetic_particle_force_N": np.asarray(tr.magnetic_particle_force).tolist(),
            "resistance_ohm": tr.resistance_ohm, "inductance_H": tr.inductance_H,
            "turns": tr.turns, "source": tr.source,
            "offsets_m": _list(tr.offsets),
            "villari_by_offset_Wb_per_N": _list(tr.villari_by_offset),
            "approach_by_offset_Wb_per_m": _list(tr.approach_by_offset)}
    return {"schema": "msens.transducers/3", "transducers": trs, "details": report.details}


def _from_json(data: dict) -> TransducerReport:
    require(data.get("schema") == "msens.transducers/3",
            f"not a transducer cache file (schema {data.get('schema')!r})")
    out = {}
    for v in data["transducers"].values():
        out[int(v["particle"])] = Transducer(
            particle=int(v["particle"]), contacts=np.array(v["contacts"], dtype=int),
            sensitivity_villari=np.array(v["sensitivity_villari_Wb_per_N"]),
            dlambda_dapproach=np.array(v["dLambda_dapproach_Wb_per_m"]),
            contact_stiffness=float(v["contact_stiffness_N_per_m1.5"]),
            reference_force=float(v["reference_force_N"]),
            magnetic_particle_force=np.array(v["magnetic_particle_force_N"]),
            resistance_ohm=float(v["resistance_ohm"]), inductance_H=float(v["inductance_H"]),
            turns=int(v["turns"]), source=str(v["source"]),
            offsets=_array(v.get("offsets_m")),
            villari_by_offset=_array(v.get("villari_by_offset_Wb_per_N")),
            approach_by_offset=_array(v.get("approach_by_offset_Wb_per_m")))
    return TransducerReport(out, data.get("details", {}))


def _list(a: np.ndarray | None) -> list | None:
    return None if a is None else np.asarray(a).tolist()


def _array(v: list | None) -> np.ndarray | None:
    return None if v is None else np.array(v, dtype=float)


def transducer_report(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                      cache_dir: str | Path | None = None, mesh_dir: str | Path | None = None,
                      stress_force: float | None = None,
                      law: JilesAthertonSablik | None = None,
                      material: ElasticMaterial = BEAD_STEEL, approach: bool = True,
                      refresh: bool = False) -> TransducerReport:
    """Cached :func:`compute_transducers` (``transducer-<key>.json``).

    Lookup follows the mesh cache (:mod:`msens.field.cache`): with ``cache_dir`` only that
    folder; otherwise the committed folders (:func:`msens.field.cache.committed_mesh_dirs`,
    where the project commits the transducers of its default studies beside their meshes),
    and new results go to :func:`msens.field.cache.default_mesh_dir` (the user cache, never
    the committed ``meshes/``). ``refresh`` recomputes.
    """
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    law = law_for_steel(geometry.steel) if law is None else law
    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    approach=approach)
    name = f"transducer-{key}.json"
    if cache_dir is not None:
        directory = Path(cache_dir)
        search = [directory]
    else:
        directory = default_mesh_dir()
        search = [*committed_mesh_dirs(), directory]
    if not refresh:
        for d in search:
            path = d / name
            if path.is_file():
                _log.info("transducers %s (cached: yes, %s)", key, path)
                try:
                    return _from_json(json.loads(path.read_text()))
                except (ValueError, KeyError) as exc:
                    raise InputError(f"transducer cache {path} is unreadable ({exc}); "
                                     "delete it") from exc
    _log.info("transducers %s (cached: no): computing them, usually under a minute", key)
    report = compute_transducers(geometry, options=options, mesh_dir=mesh_dir,
                                 stress_force=force, law=law, material=material,
                                 approach=approach)
    directory.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(directory / name, json.dumps(_to_json(report), indent=1).encode(),
                       overwrite=True)
    _log.info("transducers %s cached in %s", key, directory / name)
    return report


def transducers_for(geometry: SensorGeometry, **kwargs) -> dict[int, Transducer]:
    """One :class:`Transducer` per coil of ``geometry``, keyed by particle (cached on disk).

    Keyword arguments as :func:`transducer_report`.
    """
    return transducer_report(geometry, **kwargs).transducers


__all__ = [
    "MECHANISMS",
    "OFFSET_SPAN",
    "OFFSET_STEP",
    "TRANSDUCER_VERSION",
    "ContactRates",
    "MechanismPotentials",
    "Transducer",
    "TransducerReport",
    "adjoint_check",
    "bias_solution",
    "cache_key",
    "coil_linkage",
    "compute_transducers",
    "contact_forces_of",
    "contact_profiles",
    "contact_rates",
    "emf",
    "emf_from_rates",
    "magnetic_precompression",
    "mechanism_potentials",
    "offset_profiles",
    "open_contact_emf",
    "particle_forces",
    "rigid_translation_emf",
    "transducer_report",
    "transducers_for",
]
