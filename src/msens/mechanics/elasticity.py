"""Axisymmetric linear elasticity on a meridian section (scikit-fem, P2).

The weak form is the axisymmetric one: strains (d_r u_r, d_z u_z, u_r/r, d_z u_r + d_r u_z)
and every integral weighted by r. :func:`solve_traction` solves for a given surface
traction with u_z = 0 on the equator and u_r = 0 on the axis; :func:`axisymmetric_stress`
gives the stress (rr, zz, tt, rz) of a displacement. Used by :mod:`msens.mechanics.beadstress`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla
import skfem
from skfem import BilinearForm, LinearForm


def lame_parameters(youngs_modulus: float, poisson_ratio: float) -> tuple[float, float]:
    """Lamé parameters (lambda, mu), Pa, of an isotropic solid."""
    lam = youngs_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))
    return lam, youngs_modulus / (2 * (1 + poisson_ratio))


def _strains(u, r):
    """Axisymmetric engineering strains (e_rr, e_zz, e_thth, gamma_rz) of a vector field."""
    g = u.grad
    return g[0][0], g[1][1], u[0] / r, g[0][1] + g[1][0]


def axisymmetric_stress(u, r, lam: float, mu: float) -> tuple:
    """Stresses of an axisymmetric displacement field inside an skfem form.

    Parameters
    ----------
    u : skfem DiscreteField
        Displacement (u_r, u_z), m: ``u[i]`` shape (...), ``u.grad`` (2, 2, ...).
    r : ndarray
        Radial coordinate of the quadrature points, m (> 0 there).
    lam, mu : float
        Lamé parameters, Pa.

    Returns
    -------
    tuple of 4 ndarrays
        (sigma_rr, sigma_zz, sigma_thth, sigma_rz), Pa.
    """
    err, ezz, ett, grz = _strains(u, r)
    tr = lam * (err + ezz + ett)
    return tr + 2 * mu * err, tr + 2 * mu * ezz, tr + 2 * mu * ett, mu * grz


@BilinearForm
def _stiffness(u, v, w):
    """r-weighted axisymmetric elastic energy form (the 2 pi is dropped on both sides)."""
    r = w.x[0]
    s = axisymmetric_stress(u, r, w.lam, w.mu)
    e = _strains(v, r)
    return (s[0] * e[0] + s[1] * e[1] + s[2] * e[2] + s[3] * e[3]) * r


Traction = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                    tuple[np.ndarray, np.ndarray]]


def solve_traction(mesh: skfem.Mesh, youngs_modulus: float, poisson_ratio: float,
                   traction: Traction, facets: np.ndarray, *, intorder: int = 8
                   ) -> tuple[skfem.CellBasis, np.ndarray]:
    """Axisymmetric elasticity on a quarter section with tractions on given facets.

    Symmetry conditions: u_r = 0 on the boundary ``"axis"`` and u_z = 0 on ``"equator"``;
    every other boundary facet not in ``facets`` is traction-free.

    Parameters
    ----------
    mesh : skfem.Mesh
        Triangle mesh in (r, s) coordinates, m, with boundaries "axis" and "equator"
        (e.g. from :func:`msens.mechanics.beadmesh.bead_section_mesh`).
    youngs_modulus, poisson_ratio : float
        E (Pa) and nu.
    traction : callable
        ``traction(r, s, n_r, n_z) -> (t_r, t_z)``: traction (Pa) at facet quadrature
        points from their coordinates and outward unit normal; arrays of equal shape.
    facets : ndarray of int
        Loaded facets.
    intorder : int
        Facet quadrature order.

    Returns
    -------
    basis : skfem.CellBasis
        P2 vector basis.
    u : ndarray, shape (basis.N,)
        Displacement dofs, m.
    """
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTriP2()))
    lam, mu = lame_parameters(youngs_modulus, poisson_ratio)
    K = _stiffness.assemble(basis, lam=lam, mu=mu)

    @LinearForm
    def load(v, w):
        t_r, t_z = traction(w.x[0], w.x[1], w.n[0], w.n[1])
        return (t_r * v[0] + t_z * v[1]) * w.x[0]

    fb = skfem.FacetBasis(mesh, basis.elem, facets=facets, intorder=intorder)
    f = load.assemble(fb)
    axis, equator = basis.get_dofs("axis"), basis.get_dofs("equator")
    fixed = np.concatenate([axis.nodal["u^1"], axis.facet["u^1"],
                            equator.nodal["u^2"], equator.facet["u^2"]])
    return basis, skfem.solve(*skfem.condense(K, f, D=fixed), solver=_direct)


def _direct(A, b, **_):
    """Sparse direct solve (SuperLU, default COLAMD ordering) of the SPD system.

    COLAMD measured faster than MMD on A + A^T here (refine 2: 1.9 s against 5.2 s).
    """
    return spla.spsolve(A.tocsc(), b)


def _project_stress(basis, sbasis, u, lam, mu) -> np.ndarray:
    """Element-wise L2 projection of the four stress components onto discontinuous P2.

    sigma_rr, sigma_zz and sigma_rz are linear in each element (P2 displacement), hence
    reproduced exactly; the hoop stress contains u_r / r and is projected.
    """
    ui = skfem.Basis(basis.mesh, basis.elem, quadrature=sbasis.quadrature).interpolate(u)

    @BilinearForm
    def mass(s, q, w):
        return s * q

    M = mass.assemble(sbasis)
    lu = spla.splu(M.tocsc())
    out = np.empty((4, sbasis.N))
    for k in range(4):
        @LinearForm
        def rhs(q, w, k=k):
            return axisymmetric_stress(w.u, w.x[0], lam, mu)[k] * q

        out[k] = lu.solve(rhs.assemble(sbasis, u=ui))
    return out
