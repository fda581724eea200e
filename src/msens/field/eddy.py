"""Time-harmonic small-signal (eddy-current) solver for the axisymmetric A_φ problem.

Sign and time convention
------------------------
Phasors are *peak* amplitudes with the engineering convention x(t) = Re(X e^{jωt}). Faraday's
law gives curl E = −jω B. In the axisymmetric A_φ formulation E has only a φ component and no
electric scalar potential can drive an azimuthal current (∂V/∂φ = 0; no applied voltage, no
gauge freedom), so E_φ = −jω A_φ and the induced current density is

    J_φ = σ E_φ = −jω σ A_φ.

Ampère's law curl H = J_s + J_φ in the weak form of :mod:`.forms` then reads

    ∫ ν_t B(a) · B(v) r dr dz + jω ∫ σ a v r dr dz = ∫ J_s v r dr dz,
    i.e.  (K_t + jω M_σ) a = f,

with K_t the stiffness (linear ν, or the tangent reluctivity dH/dB at a bias point, A/r
terms included) and M_σ the conductivity mass matrix of the conducting regions. Losses make
responses lag: a lossy body in a field H0 has Im(m/H0) < 0 and absorbs the time-average power
P = −(ω μ0/2) Im(m H0*). With the physicists' e^{−iωt} every phasor here is conjugated.

The solver factorises the complex K_t + jω M_σ once per frequency (SuperLU in the pattern's
nested-dissection order, :mod:`.linsolve`; :class:`HarmonicOperator` keeps the assembled
matrices and solves many right-hand sides per factor); K_t and M_σ are assembled
once on the cached sparsity pattern of :mod:`.assembly` (its ``np.bincount`` assembly is
real, so the two real matrices are combined on their common pattern).
scikit-fem could assemble complex forms directly (``BilinearForm(dtype=np.complex128)``) and
``skfem.solve`` wraps ``spsolve``; neither reuses the cached pattern or the factor.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import skfem

from msens.errors import require
from msens.field.assembly import assemble_matrix, assemble_vector
from msens.field.constitutive import small_signal_tangent
from msens.field.forms import (
    element_load,
    element_mass,
    element_stiffness,
    flux_density_qp,
    potential_qp,
)
from msens.field.linsolve import SparseLU, factorize
from msens.field.mesh import AxiMesh
from msens.field.regions import CurrentRegion
from msens.field.solve import Discretisation, FieldSolution, MagnetostaticProblem, discretise
from msens.params.units import MU0, TWO_PI
from msens.progress import timed

_log = logging.getLogger(__name__)

#: Element size at the surface of every conducting part for the eddy-current model (the beads
#: near a coil, the pole pieces, the magnets: :func:`msens.field.build.skin_surface_size`), m
#: (the skin depth is ~20 µm at 100 kHz with the differential permeability). On the main study
#: (``python benchmarks/dynamic_mesh_convergence.py``) coil 13's contact approach with 30 µm at
#: the beads agrees with a reference (beads 20 µm, pole surfaces 10 µm) within 0.04 % and
#: 0.01° at 10–30 kHz and 0.5 % and 0.04° at 100 kHz, R_eddy within 1.0 % and L within
#: 0.2 %; at 40 µm everywhere the contact approach was 1.1 % off at 100 kHz, and with the bead
#: surfaces only graded (the pole pieces at their part size) 6.3° off at 10 kHz, 27 % at
#: 100 kHz and R_eddy +130 % at 10 kHz.
SKIN_SIZE = 30e-6

__all__ = ["SKIN_SIZE", "HarmonicOperator", "HarmonicSolution",
           "conductivity", "conductivity_mass", "dipole_moment",
           "dissipated_power", "harmonic_flux_linkage", "mean_field_z", "skin_depth",
           "solve_harmonic", "winding_impedance"]


@dataclass(frozen=True)
class HarmonicSolution:
    """Time-harmonic solution at one frequency.

    Attributes
    ----------
    frequency : float
        f, Hz (ω = 2π f).
    a : ndarray of complex, shape (n_dofs,)
        Peak phasor of A_φ at the dofs, T m.
    basis : skfem.CellBasis
    disc : Discretisation
        Quadrature data, pattern and Dirichlet dofs (shared with the static model).
    nu : ndarray, shape (n_elements, n_qp) or (n_elements, n_qp, 2, 2)
        Reluctivity (scalar or tangent tensor) used in K_t, m/H.
    sigma : ndarray, shape (n_elements,)
        Conductivity, S/m.
    j_source : ndarray of complex, shape (n_elements,)
        Imposed (winding) current density phasor, A/m².
    residual : float
        Relative residual ‖A a − b‖/‖b‖ of the free-dof system.
    """

    frequency: float
    a: np.ndarray = field(repr=False, compare=False)
    basis: skfem.CellBasis = field(repr=False, compare=False)
    disc: Discretisation = field(repr=False, compare=False)
    nu: np.ndarray = field(repr=False, compare=False)
    sigma: np.ndarray = field(repr=False, compare=False)
    j_source: np.ndarray = field(repr=False, compare=False)
    residual: float = 0.0

    @property
    def omega(self) -> float:
        """Angular frequency ω = 2π f, rad/s."""
        return TWO_PI * self.frequency

    @property
    def dofs(self) -> int:
        """Number of dofs (including Dirichlet ones)."""
        return int(self.a.size)


def conductivity(mesh: AxiMesh, values: Mapping[str, float]) -> np.ndarray:
    """Conductivity per element from per-subdomain values (0 elsewhere).

    Parameters
    ----------
    mesh : AxiMesh
    values : Mapping[str, float]
        σ (S/m, >= 0) of each conducting subdomain.

    Returns
    -------
    ndarray, shape (n_elements,)
        S/m.
    """
    sigma = np.zeros(mesh.n_elements)
    for name, s in values.items():
        require(name in mesh.subdomains,
                f"conducting region '{name}' is not a mesh subdomain "
                f"(have {sorted(mesh.subdomains)})")
        require(s >= 0, f"conductivity of '{name}' must be >= 0, got {s}")
        sigma[mesh.subdomains[name]] = s
    return sigma


def skin_depth(frequency: float, mu_r: float, sigma: float) -> float:
    """δ = √(2/(ω μ σ)), m (μ = μ_r μ0); inf at zero frequency or conductivity."""
    w = TWO_PI * frequency * mu_r * MU0 * sigma
    return math.inf if w == 0 else math.sqrt(2.0 / w)


def conductivity_mass(disc: Discretisation, sigma: np.ndarray
                      ) -> tuple[sp.csr_matrix, sp.csc_matrix]:
    """Conductivity mass matrix M_σ = ∫ σ φ_i φ_j r dr dz (per radian).

    Parameters
    ----------
    disc : Discretisation
        Basis data and sparsity pattern (:func:`msens.field.solve.discretise`).
    sigma : ndarray, shape (n_elements,)
        S/m.

    Returns
    -------
    full : csr_matrix, shape (n_dofs, n_dofs)
        S m² (per radian).
    free : csc_matrix, shape (n_free, n_free)
        Its free–free block, on the same pattern as the stiffness's.
    """
    return assemble_matrix(disc.pattern, element_mass(disc.quad, np.asarray(sigma, float)))


class HarmonicOperator:
    """K_t and M_σ of a model assembled once; K_t + jωM_σ factorised per frequency.

    For many right-hand sides at once (the sources of a transducer, a coil's winding):
    :func:`solve_harmonic` solves one load per frequency with the same algebra.

    Parameters
    ----------
    model : MagnetostaticProblem or FieldSolution
        As :func:`solve_harmonic` (a bias state: tangent reluctivity, zero boundary values).
    sigma : ndarray, shape (n_elements,)
        Conductivity per element, S/m.

    Attributes
    ----------
    disc : Discretisation
    nu : ndarray, shape (n_elements, n_qp) or (n_elements, n_qp, 2, 2)
        Reluctivity in K_t, m/H.
    sigma : ndarray, shape (n_elements,)
    """

    def __init__(self, model: MagnetostaticProblem | FieldSolution, sigma: np.ndarray):
        sigma = np.asarray(sigma, dtype=float)
        d, nu, _, _ = _setup(model, {}, None)
        require(sigma.shape == (d.quad.w.shape[0],),
                f"sigma must have shape ({d.quad.w.shape[0]},) (one value per element), got "
                f"{sigma.shape}")
        require(bool(np.all(sigma >= 0)), "sigma must be >= 0")
        self.disc, self.nu, self.sigma = d, nu, sigma
        self.k_full, self.k_ff = assemble_matrix(d.pattern, element_stiffness(d.quad, nu))
        self.m_full, self.m_ff = conductivity_mass(d, sigma)

    def factor(self, frequency: float) -> SparseLU:
        """Factor of K_t + jωM_σ (free dofs) at ``frequency`` (Hz, >= 0); at 0 Hz the real
        K_t alone, factorised as the magnetostatic solver does."""
        require(frequency >= 0, f"frequency must be >= 0 Hz, got {frequency}")
        if frequency == 0.0:
            return factorize(self.k_ff)
        return factorize(self.matrix(frequency))

    def matrix(self, frequency: float) -> sp.csc_matrix:
        """K_t + jωM_σ on the free dofs, complex."""
        w = TWO_PI * float(frequency)
        # K and M share one pattern, so their data arrays add entry by entry
        return sp.csc_matrix((self.k_ff.data + 1j * w * self.m_ff.data, self.k_ff.indices,
                              self.k_ff.indptr), shape=self.k_ff.shape)

    def winding_load(self, region: str, current_density: float) -> np.ndarray:
        """Load vector ∫ J φ_i r dr dz (per radian) of a uniform J in ``region``, (n_dofs,)."""
        q, mesh = self.disc.quad, self.disc.basis.mesh
        require(region in (mesh.subdomains or {}), f"'{region}' is not a mesh subdomain")
        j = np.zeros(q.w.shape[0])
        j[mesh.subdomains[region]] = current_density
        return assemble_vector(q.dofs, element_load(q, j, np.zeros_like(j)), self.disc.basis.N)

    def solve(self, factor: SparseLU, loads: np.ndarray) -> np.ndarray:
        """Potentials of load vectors with A = 0 on the Dirichlet boundary.

        Parameters
        ----------
        factor : from :meth:`factor`
        loads : ndarray, shape (n_src, n_dofs)
            Real or complex, per radian.

        Returns
        -------
        ndarray of complex, shape (n_src, n_dofs)
            A_φ dofs, T m per unit source.
        """
        loads = np.atleast_2d(loads)
        free = self.disc.pattern.free
        out = np.zeros(loads.shape, dtype=complex)
        if free.size and loads.shape[0]:
            out[:, free] = factor.solve(np.ascontiguousarray(loads[:, free].T)).T
        return out

    def harmonic_solution(self, frequency: float, a: np.ndarray,
                          j_source: np.ndarray | None = None) -> HarmonicSolution:
        """Wrap dofs ``a`` (n_dofs,) as a :class:`HarmonicSolution` (for its post-processing)."""
        j = np.zeros(self.sigma.size, complex) if j_source is None else j_source
        return HarmonicSolution(frequency=float(frequency), a=a, basis=self.disc.basis,
                                disc=self.disc, nu=self.nu, sigma=self.sigma, j_source=j)


def _setup(model: MagnetostaticProblem | FieldSolution,
           sources: Mapping[str, CurrentRegion] | None, background_field: complex | None):
    """Discretisation, reluctivity at the quadrature points, J per element and lift."""
    if isinstance(model, FieldSolution):
        prob = model.problem
        d = model.disc if model.disc is not None else discretise(prob)
        mat = d.materials
        if mat.nonlinear:
            b = flux_density_qp(d.quad, model.a)
            nu = small_signal_tangent(mat, b)
        else:
            nu = np.broadcast_to(mat.nu[:, None], d.quad.w.shape)
        j = np.zeros(prob.mesh.n_elements, dtype=complex)
        b0 = 0.0 if background_field is None else background_field
        r = d.basis.doflocs[0, d.fixed]
        values = b0 * r / 2.0
    else:
        prob = model
        d = discretise(prob)
        mat = d.materials
        require(not mat.nonlinear,
                "solve_harmonic: the problem has nonlinear regions; solve the bias state "
                "first and pass its FieldSolution (the tangent reluctivity is used)")
        nu = np.broadcast_to(mat.nu[:, None], d.quad.w.shape)
        j = mat.j.astype(complex) if sources is None else np.zeros(mat.j.size, complex)
        if background_field is None:
            values = d.fixed_values
        else:
            values = background_field * d.basis.doflocs[0, d.fixed] / 2.0
    for name, w in (sources or {}).items():
        require(name in prob.regions and isinstance(prob.regions[name], CurrentRegion),
                f"harmonic source '{name}' is not a CurrentRegion of the problem")
        require(isinstance(w, CurrentRegion), f"harmonic source '{name}' must be a CurrentRegion")
        j[prob.mesh.subdomains[name]] = w.current_density
    lift = np.zeros(d.basis.N, dtype=complex)
    lift[d.fixed] = np.where(d.basis.doflocs[0, d.fixed] <= 0.0, 0.0, values)
    return d, nu, j, lift


def solve_harmonic(model: MagnetostaticProblem | FieldSolution, sigma: np.ndarray,
                   frequencies: Sequence[float], *,
                   sources: Mapping[str, CurrentRegion] | None = None,
                   background_field: complex | None = None,
                   load: np.ndarray | None = None) -> tuple[HarmonicSolution, ...]:
    """Solve (K_t + jω M_σ) a = f at each frequency.

    Parameters
    ----------
    model : MagnetostaticProblem or FieldSolution
        A linear problem (ν of its regions; magnets keep μ_rec, their remanence is a static
        source and does not enter), or a bias state: then K_t uses the tangent reluctivity
        dH/dB at that state (as :func:`msens.field.solve.incremental` and
        :class:`msens.magnetics.potentials.TangentOperator` do) on its mesh and basis.
    sigma : ndarray, shape (n_elements,)
        Conductivity per element, S/m (:func:`conductivity`).
    frequencies : sequence of float
        Hz, >= 0; f = 0 solves the static problem with the same operator (K_t a = f).
    sources : Mapping[str, CurrentRegion], optional
        Winding subdomains and their current-density phasors J_s (A/m², e.g. N × 1 A / S);
        the other windings carry none. Default: a problem's own windings; none for a bias
        state.
    background_field : complex, optional
        Phasor B0 (T) of a uniform axial applied field, imposed as A_φ = B0 r/2 on the
        problem's ``outer`` boundaries. Default: a problem's own boundary values
        (``background_field`` / ``outer_potential``); 0 for a bias state.
    load : ndarray, shape (n_dofs,), optional
        Extra load vector (e.g. a magnetisation source, per radian), complex allowed.

    Returns
    -------
    tuple of HarmonicSolution
        One per frequency, in the given order.
    """
    freqs = [float(f) for f in frequencies]
    require(all(f >= 0 for f in freqs), f"frequencies must be >= 0 Hz, got {freqs}")
    op = HarmonicOperator(model, sigma)
    d, _, j, lift = _setup(model, sources, background_field)
    q, n, free = d.quad, d.basis.N, d.pattern.free
    zero = np.zeros_like(op.sigma)
    f_vec = (assemble_vector(q.dofs, element_load(q, j.real, zero), n)
             + 1j * assemble_vector(q.dofs, element_load(q, j.imag, zero), n))
    if load is not None:
        require(np.shape(load) == (n,), f"load must have shape ({n},)")
        f_vec = f_vec + load
    k_lift, m_lift = op.k_full @ lift, op.m_full @ lift
    out = []
    for f in freqs:
        w = TWO_PI * f
        rhs = (f_vec - k_lift - 1j * w * m_lift)[free]
        a = lift.copy()
        if free.size:
            with timed(_log, f"harmonic solve at {f:g} Hz"):
                a[free] = op.factor(f).solve(rhs)
        a_ff = op.matrix(f)
        res = float(np.linalg.norm(a_ff @ a[free] - rhs) / max(np.linalg.norm(rhs), 1e-300))
        out.append(HarmonicSolution(frequency=f, a=a, basis=d.basis, disc=d, nu=op.nu,
                                    sigma=op.sigma, j_source=j, residual=res))
    return tuple(out)


# ----------------------------------------------------------------------------- post

def _elements(sol: HarmonicSolution, region: str | None) -> np.ndarray:
    if region is None:
        return np.arange(sol.sigma.size)
    subs = sol.basis.mesh.subdomains or {}
    require(region in subs, f"region '{region}' is not a mesh subdomain (have {sorted(subs)})")
    return np.asarray(subs[region])


def _h_of_b(nu: np.ndarray, b: np.ndarray) -> np.ndarray:
    """H = ν B (scalar or tensor ν), shape like ``b`` (n_el, n_qp, 2)."""
    if nu.ndim == 2:
        return nu[..., None] * b
    return np.einsum("eqcd,eqd->eqc", nu, b)


def dissipated_power(sol: HarmonicSolution, region: str | None = None) -> float:
    """Time-average eddy-current loss P = ½ ∫ σ|E|² dV = (ω²/2) ∫ σ |A|² 2πr dr dz, W.

    Parameters
    ----------
    sol : HarmonicSolution
    region : str, optional
        Mesh subdomain (default: every element; σ = 0 outside conductors).
    """
    el = _elements(sol, region)
    q = sol.disc.quad
    a = potential_qp(q, sol.a)[el]
    return float(0.5 * sol.omega**2 * TWO_PI
                 * np.sum(sol.sigma[el, None] * np.abs(a) ** 2 * q.w[el]))


def mean_field_z(sol: HarmonicSolution, region: str) -> complex:
    """Volume mean of H_z over a region, ∫ H_z dV / V, phasor, A/m.

    H = ν B with the model's (tangent) reluctivity, i.e. the small-signal H.
    """
    el = _elements(sol, region)
    q = sol.disc.quad
    h = _h_of_b(sol.nu[el], flux_density_qp(q, sol.a)[el])
    return complex(np.sum(h[..., 1] * q.w[el]) / np.sum(q.w[el]))


def dipole_moment(sol: HarmonicSolution, region: str) -> complex:
    """Axial magnetic dipole moment of a region, phasor, A m².

    m = ∫ (M + ½ x × J) dV over the region, with the magnetisation M = B/μ0 − H (H = ν B,
    small-signal) and J = J_s − jωσA_φ the azimuthal current density (imposed plus induced).
    For J = J_φ e_φ at x = r e_r + z e_z, (x × J)_z = r J_φ, so

        m_z = ∫ [ (1/μ0 − ν) B_z + r J_φ / 2 ] 2π r dr dz.

    Bound surface currents at the region's boundary are accounted for by M (the moment of
    a magnetised body is ∫ M dV). Far from the region its field is that of m.
    """
    el = _elements(sol, region)
    q = sol.disc.quad
    b = flux_density_qp(q, sol.a)[el]
    mz = b[..., 1] / MU0 - _h_of_b(sol.nu[el], b)[..., 1]
    j = sol.j_source[el, None] - 1j * sol.omega * sol.sigma[el, None] * potential_qp(q, sol.a)[el]
    return complex(TWO_PI * np.sum((mz + 0.5 * q.r[el] * j) * q.w[el]))


def harmonic_flux_linkage(sol: HarmonicSolution, region: str, turns: float,
                          area: float) -> complex:
    """Flux linkage of a winding in a time-harmonic solution, Λ = (N/S) ∫_region 2π r A_φ dS,
    phasor, Wb (the static one: :func:`msens.field.post.flux_linkage`).

    Parameters
    ----------
    region : str
        Winding subdomain.
    turns : float
        N.
    area : float
        Winding cross-section S, m².
    """
    el = _elements(sol, region)
    q = sol.disc.quad
    return complex(turns / area * TWO_PI * np.sum(potential_qp(q, sol.a)[el] * q.w[el]))


def winding_impedance(sol: HarmonicSolution, region: str, turns: float, area: float,
                      r_dc: float = 0.0) -> complex:
    """Impedance of the driving winding, Z = R_dc + jωΛ/I, Ω.

    The winding's current I = J S / N follows from its (uniform) imposed current density.
    The winding itself is taken as non-conducting in the field model (fine wire: no eddy
    currents in it), its resistance is ``r_dc``. Re Z − R_dc = 2P/|I|² (P the eddy loss).
    """
    el = _elements(sol, region)
    j = sol.j_source[el]
    require(bool(np.all(j == j[0])) and j[0] != 0,
            f"winding '{region}' must carry a uniform nonzero source current density")
    current = j[0] * area / turns
    return complex(r_dc + 1j * sol.omega * harmonic_flux_linkage(sol, region, turns, area)
                   / current)
