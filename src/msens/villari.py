"""Villari sensitivity of a pick-up coil to the contact forces, by reciprocity.

A small change ΔM of the magnetisation in the beads (at fixed H) changes the flux linkage of a
coil by

    ΔΛ = μ0 ∫ h1 · ΔM dV,

with h1 the coil's field strength per ampere computed at the bias point with the incremental
(tangent) permeability: in the linearised (tangent) problem ΔM enters as the source
ν_t μ0 ΔM, whose flux linkage with the coil equals, by the symmetry of the tangent operator,
the coil's own field dotted with the source (reciprocity). :func:`direct_flux_change` re-solves
the linearised problem with ΔM as the source and takes the coil's flux linkage, the check.

Magnetoelastic source. For a bead squeezed between two opposite contact forces F, the stress is
σ(r, z; F) (:mod:`msens.beadstress`); along the local bias direction ĥ it is the equivalent
uniaxial stress σ_eq (Daniel & Hubert, :func:`msens.magnetoelastic.equivalent_uniaxial_stress`),
and ΔM = (∂M/∂σ)_H(|H|) σ_eq ĥ with the JAS law's linear coefficient at σ = 0 (the contact
stresses reach GPa, outside the nonlinear law's range; the linear response at the bias point is
what a small force change produces). The bead's sensitivity to a symmetric two-pole load is

    S_i = μ0 ∫_bead (h1·ĥ) (∂M/∂σ)_H σ_eq(r, z; F) dV / F,       Wb/N.

σ/F is exactly linear in F for bead-average quantities; near the contacts it is not (the
contact radius grows as F^{1/3}), so S_i belongs to the force ``F`` at which the stress was
solved (the secant sensitivity at that force).

Per contact. Bead i carries F_{i-1} on its upper pole and F_i on its lower pole (contact c is
between particles c and c+1). Its load splits into the symmetric part (F_{i-1} + F_i)/2, which
squeezes it, and the antisymmetric part (F_i - F_{i-1})/2, which accelerates it (a body load,
m a); we keep the symmetric part only. The antisymmetric part's stress is odd about the bead's
equator and integrates to nearly zero against the nearly even field of a bead under a coil;
its neglect is the main approximation. So ∂Λ/∂F_c = (S_c + S_{c+1})/2; the wall contact (c = N)
loads bead N only: S_N/2; beads outside the field model contribute 0.

Contact reluctance (geometry). The Hertz flat a(F) = (3 F R*/(4 E*))^{1/3} grows with the force.
In the truncated-sphere model the air gap outside the flat is g(r) = (r² - a²)/R, so growing the
flat by δa closes the whole wedge by 2a δa/R: to first order the flat's growth *is* the
approach of the two beads (the sliver of wedge the rim sweeps has volume O(δa²)). The mechanism
is therefore computed as ∂Λ/∂F_c = (∂Λ_bias/∂δ_c)(dδ/dF), with δ_c the approach at contact c
(every bead above c moving rigidly toward the wall, coil and magnets fixed) and Hertz's
dδ/dF = 2δ/(3F) at the operating force. ∂Λ_bias/∂δ_c comes from the adjoint
dΛ/dδ = -2π a1·∂R/∂δ (a1: the coil's incremental solution; ∂R/∂δ: central difference of the
bias residual on morphed meshes of the same topology), checked by re-solving the nonlinear
problem on the morphed meshes (:func:`approach_flux_change`). Re-meshing at a different flat
radius was tried first and rejected: the mesh-to-mesh noise of the coil's bias flux linkage
(~1e-4 relative) is about 1000 times the effect.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import skfem
from matplotlib.tri import Triangulation

from msens.beadstress import BeadStress, solve_bead_stress, stress_at
from msens.errors import require
from msens.field.assembly import assemble_matrix, assemble_vector, factorize
from msens.field.constitutive import reluctivities, tangent
from msens.field.forms import (
    element_stiffness,
    flux_density_qp,
    potential_qp,
    quadrature_data,
)
from msens.field.geometry import Coil, SensorGeometry
from msens.field.mesh import from_arrays
from msens.field.regions import Winding
from msens.field.sensor_model import shell_function
from msens.field.solve import FieldSolution, incremental, internal_field_strength
from msens.magnetoelastic import (
    DEFAULT_STEEL,
    JilesAthertonSablik,
    equivalent_uniaxial_stress,
    stress_sensitivity,
)
from msens.materials import BEAD_STEEL, ElasticMaterial
from msens.units import MU0

TWO_PI = 2.0 * math.pi


# ----------------------------------------------------------------------------- bead stress

class StressSampler:
    """Fast evaluation of a bead's stress per newton at many points.

    :func:`msens.beadstress.stress_at` locates each point by Newton iterations in a dozen
    candidate elements (about 0.4 ms per point); here the straight-sided triangulation of the
    stress mesh's vertices finds the element (matplotlib's trapezoid map), two Newton steps of
    the isoparametric map give the reference coordinates (exact for interior elements), and
    points outside the straight triangulation (between a chord and the sphere) fall back to
    ``stress_at``.

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


# ----------------------------------------------------------------------------- reciprocity

@dataclass(frozen=True)
class BeadState:
    """Bias and coil fields at the quadrature points of the beads (one coil).

    Attributes
    ----------
    coil : Coil
    h_bias : ndarray, shape (n_elements, n_qp, 2)
        Bias H, A/m (every element of the mesh; used in bead elements only).
    h_coil : ndarray, shape (n_elements, n_qp, 2)
        Coil's incremental H per ampere, 1/m.
    z : ndarray, shape (n_elements, n_qp)
        Axial coordinate of the quadrature points, m.
    incremental : FieldSolution
        The coil's linearised solution (1 A).
    """

    coil: Coil
    h_bias: np.ndarray
    h_coil: np.ndarray
    z: np.ndarray
    incremental: FieldSolution


def bead_state(sol: FieldSolution, coil: Coil) -> BeadState:
    """Bias H and the coil's incremental H per ampere at every quadrature point."""
    name = f"coil_{coil.particle}"
    inc = incremental(sol, {name: Winding(coil.turns / coil.area)})
    q = sol.disc.quad
    b0 = flux_density_qp(q, sol.a)
    nu, _ = reluctivities(sol.disc.materials, b0)
    h0 = nu[..., None] * b0
    h0[..., 1] -= sol.disc.materials.hc[:, None]
    z = np.asarray(sol.basis.global_coordinates())[1]
    return BeadState(coil=coil, h_bias=h0, h_coil=internal_field_strength(inc), z=z,
                     incremental=inc)


def stress_magnetisation(sol: FieldSolution, state: BeadState, sampler: StressSampler,
                         elements: np.ndarray, z_center: float,
                         law: JilesAthertonSablik = DEFAULT_STEEL) -> np.ndarray:
    """ΔM per newton of a symmetric two-pole load at the quadrature points of one bead.

    Parameters
    ----------
    sol : FieldSolution
        Bias solution.
    state : BeadState
    sampler : StressSampler
    elements : ndarray of int, shape (k,)
        The bead's elements.
    z_center : float
        The bead centre, m.
    law : JilesAthertonSablik

    Returns
    -------
    ndarray, shape (k, n_qp, 2)
        ΔM / F = (∂M/∂σ)_H(|H|) σ_eq/F ĥ, A/m/N.
    """
    q = sol.disc.quad
    r = q.r[elements]
    dz = state.z[elements] - z_center
    # stay inside the sphere of the stress model (the field bead's chords lie inside it)
    rho = np.hypot(r, dz)
    k = np.minimum(1.0, sampler.bs.radius / np.maximum(rho, 1e-300))
    stress = sampler(r * k, dz * k)
    h = state.h_bias[elements]
    hmag = np.hypot(h[..., 0], h[..., 1])
    sig = equivalent_uniaxial_stress(stress, h)
    coef = stress_sensitivity(law, hmag, 0.0)
    hhat = h / np.where(hmag > 0, hmag, 1.0)[..., None]
    return (coef * sig)[..., None] * hhat


def reciprocity_flux(sol: FieldSolution, state: BeadState, elements: np.ndarray,
                     dm: np.ndarray) -> float:
    """ΔΛ = μ0 ∫ h1 · ΔM dV over ``elements``, Wb (per the units of ΔM)."""
    w = sol.disc.quad.w[elements]
    return MU0 * TWO_PI * float(np.sum(w * np.einsum("eqc,eqc->eq", state.h_coil[elements],
                                                     dm)))


class TangentOperator:
    """The factorised tangent (incremental) stiffness at a bias point, for many sources."""

    def __init__(self, sol: FieldSolution):
        d = sol.disc
        b0 = flux_density_qp(d.quad, sol.a)
        nu, nu_d = reluctivities(d.materials, b0)
        self.sol = sol
        self.nu_t = tangent(b0, nu, nu_d)
        _, ff = assemble_matrix(d.pattern, element_stiffness(d.quad, self.nu_t))
        self._lu = factorize(ff)

    def solve_magnetisation(self, elements: np.ndarray, dm: np.ndarray) -> np.ndarray:
        """Dofs of the linearised field of a magnetisation source ΔM in ``elements``.

        The weak form of B = μ_t H + μ0 ΔM is ∫ ν_t B(A)·B(v) r = ∫ ν_t μ0 ΔM · B(v) r, with
        A = 0 on the Dirichlet boundary. Returns A, shape (n_dofs,).
        """
        d = self.sol.disc
        q = d.quad
        src = MU0 * np.einsum("eqcd,eqd->eqc", self.nu_t[elements], dm)
        fe = np.einsum("eqic,eqc->ei", q.g[elements], src * q.w[elements][..., None])
        f = assemble_vector(q.dofs[:, elements], fe, d.basis.N)
        a = np.zeros(d.basis.N)
        free = d.pattern.free
        a[free] = self._lu.solve(f[free])
        return a


def nonlinear_flux_change(sol: FieldSolution, elements: np.ndarray, dm: np.ndarray,
                          coil: Coil, scale: float, *, tol: float = 1e-11,
                          max_iter: int = 20) -> float:
    """dΛ/dε of the full nonlinear problem with the magnetisation ε ΔM added in ``elements``.

    The constitutive law becomes H = H_law(B - μ0 ε ΔM) (magnets keep their remanence);
    Newton from the bias state converges in a few steps for small ε. The central difference
    (Λ(+ε) - Λ(-ε)) / (2ε) with ε = ``scale`` checks the tangent, the incremental solve and
    reciprocity at once (error O(ε²)).

    Returns
    -------
    float
        Wb per unit of ΔM's scale (Wb/N for ΔM per newton).
    """
    d = sol.disc
    q = d.quad
    free = d.pattern.free
    mat = d.materials
    lam = []
    for eps in (scale, -scale):
        shift = np.zeros_like(q.w)[..., None] * np.zeros(2)
        shift[elements] = MU0 * eps * dm
        a = sol.a.copy()
        for _ in range(max_iter):
            b = flux_density_qp(q, a) - shift
            nu, nu_d = reluctivities(mat, b)
            h = nu[..., None] * b
            h[..., 1] -= mat.hc[:, None]
            fe = np.einsum("eqic,eqc->ei", q.g, h * q.w[..., None])
            res = assemble_vector(q.dofs, fe, d.basis.N)[free]
            _, ff = assemble_matrix(d.pattern, element_stiffness(q, tangent(b, nu, nu_d)))
            da = factorize(ff).solve(-res)
            a[free] += da
            if np.linalg.norm(da) <= tol * np.linalg.norm(a[free]):
                break
        lam.append(coil_flux_linkage(sol, a, coil))
    return (lam[0] - lam[1]) / (2 * scale)


def coil_flux_linkage(sol: FieldSolution, a: np.ndarray, coil: Coil) -> float:
    """Λ = (N/S) ∫_coil 2π r A dS of dofs ``a`` on ``sol``'s mesh, Wb."""
    el = sol.problem.mesh.subdomains[f"coil_{coil.particle}"]
    q = sol.disc.quad
    return coil.turns / coil.area * TWO_PI * float(np.sum(potential_qp(q, a)[el] * q.w[el]))


@dataclass(frozen=True)
class VillariResult:
    """Per-bead Villari sensitivities of one coil.

    Attributes
    ----------
    coil_particle : int
    particles : ndarray of int, shape (n_beads,)
        Modelled beads, top to bottom.
    sensitivity : ndarray, shape (n_beads,)
        S_i by reciprocity, Wb/N (flux-linkage change per newton of symmetric load on bead i).
    direct : ndarray, shape (n_beads,)
        The same from the re-solved linearised problem (NaN where not computed), Wb/N.
    stress_force : float
        Force at which the bead stress was solved, N.
    """

    coil_particle: int
    particles: np.ndarray
    sensitivity: np.ndarray
    direct: np.ndarray
    stress_force: float

    @property
    def relative_error(self) -> float:
        """max |S - S_direct| / max |S| over the beads checked (NaN if none)."""
        ok = np.isfinite(self.direct)
        if not ok.any():
            return math.nan
        scale = float(np.max(np.abs(self.sensitivity)))
        return float(np.max(np.abs(self.sensitivity[ok] - self.direct[ok]))) / scale \
            if scale > 0 else 0.0


def villari_sensitivities(sol: FieldSolution, geometry: SensorGeometry, coil: Coil,
                          bs: BeadStress, *, law: JilesAthertonSablik = DEFAULT_STEEL,
                          direct: bool | Sequence[int] = False,
                          operator: TangentOperator | None = None,
                          sampler: StressSampler | None = None,
                          state: BeadState | None = None) -> VillariResult:
    """Villari sensitivity S_i of ``coil`` to a symmetric load on each modelled bead.

    Parameters
    ----------
    sol : FieldSolution
        Bias solution of ``geometry``.
    geometry : SensorGeometry
    coil : Coil
        One of the geometry's coils.
    bs : BeadStress
        Bead stress at the reference force (per newton = stress / bs.force).
    law : JilesAthertonSablik
        Magnetoelastic law; (∂M/∂σ)_H at σ = 0 is used.
    direct : bool or sequence of int
        Also re-solve the linearised problem with ΔM as the source (for all beads, or for the
        listed particles) and take the coil's flux-linkage change.
    operator, sampler, state : optional
        Reused factorised tangent operator, stress sampler and bead state of ``coil``.

    Returns
    -------
    VillariResult
    """
    require(any(u.coil.particle == coil.particle for u in geometry.sensors),
            f"coil at particle {coil.particle} is not part of the geometry")
    state = state if state is not None else bead_state(sol, coil)
    require(state.coil == coil, "villari_sensitivities: state belongs to another coil")
    sampler = sampler or StressSampler(bs)
    parts = np.array(list(geometry.beads.particles))
    if direct is True:
        check = set(parts.tolist())
    elif direct is False:
        check = set()
    else:
        check = set(direct)
    if check and operator is None:
        operator = TangentOperator(sol)
    subs = sol.problem.mesh.subdomains
    s = np.zeros(parts.size)
    d = np.full(parts.size, np.nan)
    for i, p in enumerate(parts):
        el = subs[f"bead_{p}"]
        dm = stress_magnetisation(sol, state, sampler, el, geometry.beads.center(int(p)), law)
        s[i] = reciprocity_flux(sol, state, el, dm)
        if int(p) in check:
            d[i] = coil_flux_linkage(sol, operator.solve_magnetisation(el, dm), coil)
    return VillariResult(coil.particle, parts, s, d, bs.force)


def contact_sensitivity(particles: np.ndarray, bead_sensitivity: np.ndarray,
                        count: int) -> tuple[np.ndarray, np.ndarray]:
    """∂Λ/∂F_c = (S_c + S_{c+1})/2 for every contact touching a modelled bead.

    Parameters
    ----------
    particles : ndarray of int, shape (n,)
        Consecutive modelled particles (paper numbering).
    bead_sensitivity : ndarray, shape (n,)
        S_i, Wb/N.
    count : int
        Particles in the chain; contact ``count`` is the last particle on the wall.

    Returns
    -------
    contacts : ndarray of int, shape (n + 1,)
        1-based contact numbers particles[0] - 1 .. particles[-1] (contact c joins particles c
        and c + 1).
    sensitivity : ndarray, shape (n + 1,)
        Wb/N; unmodelled neighbours (and the wall) contribute nothing.
    """
    particles = np.asarray(particles, dtype=int)
    require(particles.size > 0 and np.all(np.diff(particles) == 1),
            "modelled particles must be consecutive")
    require(particles[-1] <= count, f"particle {particles[-1]} beyond the chain of {count}")
    padded = np.concatenate([[0.0], np.asarray(bead_sensitivity, dtype=float), [0.0]])
    contacts = np.arange(particles[0] - 1, particles[-1] + 1)
    return contacts, 0.5 * (padded[:-1] + padded[1:])


# ----------------------------------------------------------------------------- reluctance

def _residual(q, mat, a: np.ndarray, n: int) -> np.ndarray:
    """Bias residual ∫ (ν(B) B - H_c e_z)·B(v) r (per radian) at dofs ``a``, shape (n,)."""
    b = flux_density_qp(q, a)
    nu, _ = reluctivities(mat, b)
    h = nu[..., None] * b
    h[..., 1] -= mat.hc[:, None]
    return assemble_vector(q.dofs, np.einsum("eqic,eqc->ei", q.g, h * q.w[..., None]), n)


def _morphed_quadrature(sol: FieldSolution, points: np.ndarray):
    axi = sol.problem.mesh
    moved = from_arrays(points, axi.mesh.t, axi.subdomains, axi.boundaries)
    basis = skfem.CellBasis(moved.mesh, sol.basis.elem, intorder=2 * sol.problem.order)
    require(bool(np.array_equal(basis.element_dofs, sol.basis.element_dofs)),
            "internal: morphed mesh changed the dof numbering")
    return quadrature_data(basis)


def approach_residuals(sol: FieldSolution, geometry: SensorGeometry,
                       contacts: Sequence[int], step: float = 1e-10) -> dict[int, np.ndarray]:
    """∂R/∂δ_c of the bias residual for the approach δ_c at each contact (central difference).

    The approach δ_c moves every modelled bead above contact c (particles first..c) rigidly
    toward the wall by δ_c; the coil, magnets and the beads below stay. On the fixed mesh
    topology the beads' vertices (including the shared flat of contact c) move and the
    adjacent elements stretch, so the residual is differentiated without re-meshing noise.

    Returns
    -------
    dict of int -> ndarray, shape (n_dofs,)
        Per radian, A per metre of approach.
    """
    require(step > 0, f"step must be > 0 m, got {step}")
    b = geometry.beads
    p0 = sol.problem.mesh.mesh.p
    mat = sol.disc.materials
    out = {}
    for c in contacts:
        require(b.first <= c <= b.last, f"contact {c} is not below a modelled bead")
        phi = shell_function(sol, [f"bead_{p}" for p in range(b.first, c + 1)], layers=0)
        res = []
        for s in (step, -step):
            p = p0.copy()
            p[1] -= s * phi
            res.append(_residual(_morphed_quadrature(sol, p), mat, sol.a, sol.basis.N))
        out[int(c)] = (res[0] - res[1]) / (2 * step)
    return out


def hertz_approach_rate(force: float, radius: float,
                        material: ElasticMaterial = BEAD_STEEL) -> float:
    """dδ/dF of two identical spheres, m/N: δ = (F/A)^{2/3}, A = E√(2R)/(3(1-ν²)).

    (Johnson 1985, eq. 4.23 with R* = R/2, E* = E/(2(1-ν²)); dδ/dF = 2δ/(3F).)
    """
    require(force > 0, f"force must be > 0 N, got {force}")
    stiff = material.youngs_modulus * math.sqrt(2 * radius) / (
        3 * (1 - material.poisson_ratio**2))
    return 2.0 / 3.0 * (force / stiff) ** (2.0 / 3.0) / force


@dataclass(frozen=True)
class ReluctanceResult:
    """Contact-approach ("reluctance") sensitivity of one coil.

    Attributes
    ----------
    coil_particle : int
    contacts : ndarray of int, shape (n_c,)
        Contact numbers (upper particle).
    dlambda_dapproach : ndarray, shape (n_c,)
        ∂Λ_bias/∂δ_c, Wb/m (beads above c moving toward the wall).
    approach_rate : float
        dδ/dF at the operating force, m/N.
    sensitivity : ndarray, shape (n_c,)
        ∂Λ/∂F_c = ∂Λ/∂δ_c dδ/dF, Wb/N.
    """

    coil_particle: int
    contacts: np.ndarray
    dlambda_dapproach: np.ndarray
    approach_rate: float
    sensitivity: np.ndarray


def reluctance_sensitivity(state: BeadState, residuals: Mapping[int, np.ndarray],
                           approach_rate: float) -> ReluctanceResult:
    """∂Λ/∂F_c of the contact approach by the adjoint: dΛ/dδ = -2π a1·∂R/∂δ.

    a1 are the coil's incremental dofs per ampere (K_t a1 = f1 and Λ = 2π f1·A, K_t
    symmetric); the coil's elements do not move, so Λ depends on δ through A only.
    """
    a1 = state.incremental.a
    contacts = np.array(sorted(residuals))
    dl = np.array([-TWO_PI * float(a1 @ residuals[int(c)]) for c in contacts])
    return ReluctanceResult(state.coil.particle, contacts, dl, approach_rate,
                            dl * approach_rate)


def approach_flux_change(sol: FieldSolution, geometry: SensorGeometry, contact: int,
                         coil: Coil, step: float = 1e-9, *, tol: float = 1e-12,
                         max_iter: int = 20) -> float:
    """∂Λ_bias/∂δ_c by re-solving the nonlinear problem on the morphed meshes (the check).

    Returns
    -------
    float
        Wb/m, central difference (Λ(+step) - Λ(-step)) / (2 step).
    """
    b = geometry.beads
    phi = shell_function(sol, [f"bead_{p}" for p in range(b.first, contact + 1)], layers=0)
    p0 = sol.problem.mesh.mesh.p
    d = sol.disc
    free = d.pattern.free
    lam = []
    for s in (step, -step):
        p = p0.copy()
        p[1] -= s * phi
        q = _morphed_quadrature(sol, p)
        a = sol.a.copy()
        for _ in range(max_iter):
            bq = flux_density_qp(q, a)
            nu, nu_d = reluctivities(d.materials, bq)
            h = nu[..., None] * bq
            h[..., 1] -= d.materials.hc[:, None]
            r = assemble_vector(q.dofs, np.einsum("eqic,eqc->ei", q.g, h * q.w[..., None]),
                                d.basis.N)[free]
            _, ff = assemble_matrix(d.pattern, element_stiffness(q, tangent(bq, nu, nu_d)))
            da = factorize(ff).solve(-r)
            a[free] += da
            if np.linalg.norm(da) <= tol * np.linalg.norm(a[free]):
                break
        el = sol.problem.mesh.subdomains[f"coil_{coil.particle}"]
        lam.append(coil.turns / coil.area * TWO_PI
                   * float(np.sum(potential_qp(q, a)[el] * q.w[el])))
    return (lam[0] - lam[1]) / (2 * step)


__all__ = [
    "BeadState", "ReluctanceResult", "StressSampler", "TangentOperator", "VillariResult",
    "approach_flux_change", "approach_residuals", "bead_state", "bead_stress",
    "coil_flux_linkage", "contact_sensitivity", "hertz_approach_rate",
    "nonlinear_flux_change", "reciprocity_flux", "reluctance_sensitivity",
    "stress_magnetisation", "villari_sensitivities",
]
