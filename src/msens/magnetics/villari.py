"""Villari mechanism: the stress-induced magnetisation of the beads as a small source.

A small change ΔM of the magnetisation in the beads (at fixed H) changes the flux linkage of a
coil by ΔΛ = μ0 ∫ h1 · ΔM dV, with h1 the coil's field strength per ampere at the bias point
(incremental permeability). Equivalently ΔM drives the tangent problem with the source
f = ∫ ν_t μ0 ΔM · B(v) r, and ΔΛ is the coil's flux linkage of that field
(:mod:`msens.magnetics.potentials`, which the transducer uses; the h1 reading is its check).

Magnetoelastic source. For a bead squeezed between two opposite contact forces F, the stress is
σ(r, z; F) (:mod:`msens.mechanics.beadstress`); along the local bias direction ĥ it is the
equivalent uniaxial stress σ_eq (Daniel & Hubert,
:func:`msens.magnetics.magnetoelastic.equivalent_uniaxial_stress`), and
μ0 ΔM = d(|H|) σ_eq ĥ with the JAS law's linear piezomagnetic coefficient d = (∂B/∂σ)_H
at σ = 0 (the contact stresses reach GPa, outside the nonlinear law's range; the linear
response at the bias point is what a small force change produces). A bead's source is per newton
of symmetric load; σ/F is linear for bead-average quantities but not near the contacts (the
contact radius grows as F^{1/3}), so S_i belongs to the force at which the stress was solved
(a secant sensitivity).

Per contact. Bead i carries F_{i-1} on its upper pole and F_i on its lower pole (contact c is
between particles c and c+1). Its load splits into the symmetric part (F_{i-1} + F_i)/2, which
squeezes it, and the antisymmetric part, which accelerates it (a body load, m a); only the
symmetric part is kept: its odd stress integrates to nearly zero against the nearly even
field of a bead under a coil. So ∂Λ/∂F_c = (S_c + S_{c+1})/2; the wall contact (c = N)
loads bead N only; beads outside the field model contribute 0 (:func:`contact_sensitivity`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.tri import Triangulation

from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.field.parts import Coil
from msens.field.regions import CurrentRegion
from msens.field.solve import FieldSolution, incremental, internal_field_strength
from msens.magnetics.magnetoelastic import (
    JilesAthertonSablik,
    equivalent_uniaxial_stress,
    piezomagnetic_coefficient,
)
from msens.magnetics.potentials import nonlinear_resolve, region_linkage
from msens.mechanics.beadstress import BeadStress, solve_bead_stress
from msens.mechanics.stress_sampling import stress_at
from msens.params.materials import BEAD_STEEL, ElasticMaterial

# ----------------------------------------------------------------------------- bead stress

class StressSampler:
    """Fast evaluation of a bead's stress per newton at many points.

    :func:`msens.mechanics.stress_sampling.stress_at` locates each point by Newton iterations in
    a dozen candidate elements (about 0.4 ms per point); here the straight-sided triangulation
    of the stress mesh's vertices finds the element (matplotlib's trapezoid map), two Newton
    steps of the isoparametric map give the reference coordinates (exact for interior
    elements), and points outside the straight triangulation (between a chord and the sphere)
    fall back to ``stress_at``.

    Parameters
    ----------
    bs : BeadStress
        Solved bead (centre at the origin after :func:`stress_at`'s convention).
    """

    def __init__(self, bs: BeadStress):
        self.bs = bs
        mesh = bs.stress_basis.mesh
        self._tri = Triangulation(mesh.p[0], mesh.p[1], mesh.t.T.copy())
        self._finder = self._tri.get_trifinder()

    def __call__(self, r: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Stress per newton of contact force at points of the centred bead.

        Parameters
        ----------
        r, z : ndarray, same shape S
            Points, m (r >= 0, r² + z² <= R²; either hemisphere).

        Returns
        -------
        ndarray, shape (*S, 4)
            (σ_rr, σ_zz, σ_θθ, σ_rz) / F, Pa/N (compression negative).
        """
        bs = self.bs
        r = np.asarray(r, dtype=float)
        z = np.asarray(z, dtype=float)
        shape = r.shape
        r, z = r.ravel(), z.ravel()
        s = np.abs(z) - bs.radius  # mesh coordinate of the upper quarter
        cells = np.asarray(self._finder(r, s), dtype=np.int64)
        out = np.empty((r.size, 4))
        ok = cells >= 0
        if ok.any():
            out[ok] = self._evaluate(r[ok], s[ok], cells[ok])
            out[ok, 3] *= np.where(z[ok] < 0, -1.0, 1.0)
        if (~ok).any():
            out[~ok] = stress_at(bs, r[~ok], z[~ok])
        return (out / bs.force).reshape(*shape, 4)

    def _evaluate(self, r: np.ndarray, s: np.ndarray, cells: np.ndarray) -> np.ndarray:
        sb = self.bs.stress_basis
        mesh, mapping = sb.mesh, sb.mapping
        v = mesh.p[:, mesh.t[:, cells]]  # (2, 3, n) vertices
        e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
        det = e1[0] * e2[1] - e1[1] * e2[0]
        dx, dy = r - v[0, 0], s - v[1, 0]
        X = np.stack([(dx * e2[1] - dy * e2[0]) / det,
                      (e1[0] * dy - e1[1] * dx) / det])[:, :, None]
        x = np.stack([r, s])[:, :, None]
        for _ in range(2):  # curved boundary elements: Newton on the isoparametric map
            X = X + np.einsum("ijkl,jkl->ikl", mapping.invDF(X, cells), x - mapping.F(X, cells))
        phis = np.array([np.asarray(sb.elem.gbasis(mapping, X, k, tind=cells)[0])
                         for k in range(sb.Nbfun)])[:, :, 0]
        return np.einsum("kp,ckp->pc", phis, self.bs.stress_dofs[:, sb.element_dofs[:, cells]])


def bead_stress(geometry: SensorGeometry, force: float,
                material: ElasticMaterial = BEAD_STEEL) -> BeadStress:
    """Stress solution of one of the geometry's beads under two opposite Hertz loads ``force``."""
    return solve_bead_stress(geometry.beads.radius, material.youngs_modulus,
                             material.poisson_ratio, force)



# ----------------------------------------------------------------------------- sources

def villari_sources(sol: FieldSolution, geometry: SensorGeometry, particles: Sequence[int],
                    sampler: StressSampler, law: JilesAthertonSablik
                    ) -> list[tuple[np.ndarray, np.ndarray]]:
    """μ0 ΔM per newton of a symmetric two-pole load, in each bead's elements.

    Parameters
    ----------
    sol : FieldSolution
        Nonlinear bias state.
    geometry : SensorGeometry
    particles : sequence of int
        Beads (each a mesh subdomain ``bead_<p>``).
    sampler : StressSampler
        Bead stress at the reference force.
    law : JilesAthertonSablik
        Magnetoelastic law of the bead steel.

    Returns
    -------
    list of (elements, source)
        Per bead: element indices, shape (n_e,), and μ0 ΔM / F at their quadrature points,
        shape (n_e, n_qp, 2), T/N.
    """
    axi = sol.problem.mesh
    xq = np.asarray(sol.basis.global_coordinates())  # (2, n_el, n_qp)
    h_all = internal_field_strength(sol)
    out = []
    for p in particles:
        el = axi.subdomains[f"bead_{p}"]
        r = xq[0, el]
        z = xq[1, el] - geometry.beads.center(int(p))
        # stay inside the stress model's sphere (a truncated bead's points lie inside it
        # up to round-off)
        rho = np.hypot(r, z)
        scale = np.minimum(1.0, sampler.bs.radius / np.where(rho > 0, rho, 1.0))
        sig = sampler(r * scale, z * scale)
        h = h_all[el]
        hmag = np.hypot(h[..., 0], h[..., 1])
        hhat = h / np.where(hmag > 0, hmag, 1.0)[..., None]
        d = piezomagnetic_coefficient(law, hmag)
        out.append((el, (d * equivalent_uniaxial_stress(sig, hhat))[..., None] * hhat))
    return out


def contact_sensitivity(particles: np.ndarray, bead_sensitivity: np.ndarray,
                        count: int) -> tuple[np.ndarray, np.ndarray]:
    """∂Λ/∂F_c = (S_c + S_{c+1})/2 for every contact touching a modelled bead.

    Parameters
    ----------
    particles : ndarray of int, shape (n,)
        Consecutive modelled particles (paper numbering).
    bead_sensitivity : ndarray, shape (..., n)
        S_i, Wb/N (leading axes: e.g. coil designs).
    count : int
        Particles in the chain; contact ``count`` is the last particle on the wall.

    Returns
    -------
    contacts : ndarray of int, shape (n + 1,)
        1-based contact numbers particles[0] - 1 .. particles[-1] (contact c joins particles c
        and c + 1).
    sensitivity : ndarray, shape (..., n + 1)
        Wb/N; unmodelled neighbours (and the wall) contribute nothing.
    """
    particles = np.asarray(particles, dtype=int)
    internal(particles.size > 0 and bool(np.all(np.diff(particles) == 1)),
             "internal: modelled particles must be consecutive")
    internal(particles[-1] <= count,
             f"internal: particle {particles[-1]} beyond the chain of {count}")
    s = np.asarray(bead_sensitivity, dtype=float)
    pad = [(0, 0)] * (s.ndim - 1) + [(1, 1)]
    padded = np.pad(s, pad)
    contacts = np.arange(particles[0] - 1, particles[-1] + 1)
    return contacts, 0.5 * (padded[..., :-1] + padded[..., 1:])


# ----------------------------------------------------------------------------- checks

@dataclass(frozen=True)
class BeadState:
    """The coil's incremental field per ampere at the bias point (the adjoint reading).

    Attributes
    ----------
    coil : Coil
    h_coil : ndarray, shape (n_elements, n_qp, 2)
        Coil's incremental H per ampere, 1/m.
    incremental : FieldSolution
        The coil's linearised solution (1 A).
    """

    coil: Coil
    h_coil: np.ndarray
    incremental: FieldSolution


def bead_state(sol: FieldSolution, coil: Coil) -> BeadState:
    """The coil's incremental solution and H per ampere at every quadrature point."""
    name = f"coil_{coil.particle}"
    inc = incremental(sol, {name: CurrentRegion(coil.turns / coil.area)})
    return BeadState(coil=coil, h_coil=internal_field_strength(inc), incremental=inc)


def dof_flux_linkage(sol: FieldSolution, a: np.ndarray, coil: Coil) -> float:
    """Λ = (N/S) ∫_coil 2π r A dS of dofs ``a`` on ``sol``'s mesh, Wb."""
    return region_linkage(sol, a, f"coil_{coil.particle}", coil.turns, coil.area)


def nonlinear_flux_change(sol: FieldSolution, elements: np.ndarray, mu0_dm: np.ndarray,
                          coil: Coil, scale: float, *, tol: float = 1e-11,
                          max_iter: int = 20) -> float:
    """dΛ/dε of the full nonlinear problem with the magnetisation ε ΔM added in ``elements``.

    The constitutive law becomes H = H_law(B - ε μ0 ΔM) (magnets keep their remanence);
    Newton from the bias state converges in a few steps for small ε. The central difference
    (Λ(+ε) - Λ(-ε)) / (2ε) with ε = ``scale`` checks the tangent, the incremental solve and
    reciprocity at once (error O(ε²)).

    Returns
    -------
    float
        Wb per unit of the source's scale (Wb/N for a source per newton).
    """
    q = sol.disc.quad
    lam = []
    for eps in (scale, -scale):
        shift = np.zeros((*q.w.shape, 2))
        shift[elements] = eps * mu0_dm
        a = nonlinear_resolve(sol, q, shift, tol=tol, max_iter=max_iter)
        lam.append(dof_flux_linkage(sol, a, coil))
    return (lam[0] - lam[1]) / (2 * scale)


__all__ = [
    "BeadState",
    "StressSampler",
    "bead_state",
    "bead_stress",
    "contact_sensitivity",
    "dof_flux_linkage",
    "nonlinear_flux_change",
    "villari_sources",
]
