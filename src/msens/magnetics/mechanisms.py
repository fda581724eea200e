"""Incremental potentials of both mechanisms' sources and the coil flux linkage read from them.

:func:`mechanism_potentials` builds, with one factorisation of the tangent operator at the
bias point, the potentials of the Villari magnetisation of every bead per newton and of the
contact approach of every contact per metre; :func:`coil_linkage` reads a coil's flux
linkage of them by exact quadrature over its winding, :func:`offset_profiles` the same for
the coil moved axially (tabulated over ±:data:`OFFSET_SPAN`), and :func:`adjoint_check`
verifies the linkage against the adjoint (reciprocity) route.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from msens.field.geometry import SensorGeometry
from msens.field.parts import Coil
from msens.field.solve import FieldSolution
from msens.magnetics.approach import approach_residuals
from msens.magnetics.magnetoelastic import JilesAthertonSablik
from msens.magnetics.potentials import (
    TableGrid,
    TangentOperator,
    adjoint_linkage,
    rect_integral,
    region_linkage,
    table_grid,
    tabulate,
)
from msens.magnetics.villari import (
    StressSampler,
    bead_state,
    bead_stress,
    contact_sensitivity,
    dof_flux_linkage,
    villari_sources,
)
from msens.params.materials import BEAD_STEEL, ElasticMaterial

_log = logging.getLogger(__name__)

#: Coil offsets tabulated per transducer: ±OFFSET_SPAN in steps of OFFSET_STEP, m.
OFFSET_SPAN = 3e-3
OFFSET_STEP = 0.1e-3


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
                         material: ElasticMaterial = BEAD_STEEL,
                         approach: bool = True) -> MechanismPotentials:
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

    The seconds each stage takes go to this module's log at DEBUG.
    """
    from msens.progress import timed

    b = geometry.beads
    with timed(_log, "sources: bead stress and tangent operator"):
        sampler = StressSampler(bead_stress(geometry, stress_force, material))
        operator = TangentOperator(sol)
        particles = np.array(list(b.particles))
        sources = villari_sources(sol, geometry, particles, sampler, law)
    with timed(_log, "sources: contact-approach residuals"):
        if approach:
            res = approach_residuals(sol, geometry, list(b.particles))
            contacts = np.array(sorted(res))
            a_rhs = -np.array([res[int(c)] for c in contacts])
        else:
            contacts = np.zeros(0, dtype=int)
            a_rhs = np.zeros((0, sol.basis.N))
    with timed(_log, "sources: potential solves"):
        rhs = np.vstack([*(operator.magnetisation_rhs(el, m) for el, m in sources), a_rhs])
        pots = operator.solve(rhs)
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
    offsets = offset_grid(OFFSET_STEP)
    link = offset_linkage(model.solution, model.potentials, geometry, coil, offsets)
    _, vil, app = model.contact_profiles(link)
    return offsets, vil, app


def offset_grid(step: float) -> np.ndarray:
    """Coil offsets over ±OFFSET_SPAN in steps of ``step`` (m, dividing the span), shape (n_o,)."""
    n = round(OFFSET_SPAN / step)
    return np.arange(-n, n + 1) * step


def offset_table_grid(sol: FieldSolution, geometry: SensorGeometry, coil: Coil) -> TableGrid:
    """The table grid of :func:`offset_linkage`: the coil's radial span, its axial span
    ±OFFSET_SPAN, spacing OFFSET_STEP / 2."""
    rect = geometry.coil_rect(next(u for u in geometry.sensors
                                   if u.coil.particle == coil.particle))
    pad = 2 * OFFSET_STEP
    return table_grid(sol, (rect.r0, rect.r1),
                      (rect.z0 - OFFSET_SPAN - pad, rect.z1 + OFFSET_SPAN + pad),
                      spacing=OFFSET_STEP / 2)


def offset_linkage(sol: FieldSolution, potentials: np.ndarray, geometry: SensorGeometry,
                   coil: Coil, offsets: np.ndarray, *, grid: TableGrid | None = None
                   ) -> np.ndarray:
    """Flux linkage of every source potential with a coil moved axially by each offset.

    A summed-area table of the potentials over the coil's radial span
    (:func:`offset_table_grid`), integrated over each moved winding.

    Parameters
    ----------
    potentials : ndarray, shape (n_s, n_dofs)
        Real (static) or complex (harmonic) A_φ dofs per unit source.
    offsets : ndarray, shape (n_o,)
        m, within ±OFFSET_SPAN.
    grid : TableGrid, optional
        :func:`offset_table_grid` of this model and coil, when it serves many calls.

    Returns
    -------
    ndarray, shape (n_o, n_s)
        Wb per unit source (complex if the potentials are).
    """
    rect = geometry.coil_rect(next(u for u in geometry.sensors
                                   if u.coil.particle == coil.particle))
    offsets = np.asarray(offsets, dtype=float)
    table = tabulate(grid or offset_table_grid(sol, geometry, coil), potentials)
    ones = np.ones(offsets.size)
    return coil.turns / coil.area * rect_integral(table, rect.r0 * ones, rect.r1 * ones,
                                                  rect.z0 + offsets, rect.z1 + offsets)


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
    inductance = dof_flux_linkage(sol, state.incremental.a, coil)
    return inductance, float(np.max(np.abs(adj - linkage))) / scale


__all__ = [
    "OFFSET_SPAN",
    "OFFSET_STEP",
    "MechanismPotentials",
    "adjoint_check",
    "coil_linkage",
    "contact_profiles",
    "mechanism_potentials",
    "offset_profiles",
]
