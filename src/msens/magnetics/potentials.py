"""Small sources at the bias point, their incremental potentials and their flux linkage.

Every MsS mechanism is a small source in the linearised (tangent) problem at the bias point,
K_t a_s = f_s, with K_t the tangent stiffness (incremental permeability):

- Villari: a bead's stress-induced magnetisation ΔM, f = ∫ ν_t μ0 ΔM · B(v) r dr dz
  (:func:`msens.magnetics.villari.villari_sources`);
- contact approach: the beads above a contact moving toward the wall, f = -∂R/∂δ_c, the
  derivative of the bias residual on morphed meshes
  (:func:`msens.magnetics.approach.approach_residuals`).

The coil is air, so its position and size do not enter a_s: the flux-linkage change of ANY
coil of N turns on the rectangle [r0, r1] × [z0, z1] is (N/S) ∫∫ 2π r a_s dr dz. One
factorisation of K_t and one back-substitution per source therefore serve the run's coils
(exact mesh quadrature over the coil region, :func:`region_linkage`) and every coil of a
design sweep (a summed-area table, :func:`linkage_table` and :func:`rect_integral`). Because
K_t is symmetric, this equals the adjoint reading ΔΛ = μ0 ∫ h1 · ΔM dV with the coil's own
incremental field h1 (the check in :mod:`msens.magnetics.transducer`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from msens.errors import internal
from msens.field.assembly import assemble_matrix, assemble_vector
from msens.field.constitutive import reluctivities, small_signal_tangent, tangent
from msens.field.forms import element_stiffness, flux_density_qp
from msens.field.linsolve import factorize
from msens.field.probes import p2_probes
from msens.field.solve import FieldSolution
from msens.params.units import TWO_PI


class TangentOperator:
    """The factorised tangent stiffness K_t at a bias point, for many right-hand sides.

    Parameters
    ----------
    sol : FieldSolution
        Nonlinear bias solution.
    """

    def __init__(self, sol: FieldSolution):
        d = sol.disc
        b0 = flux_density_qp(d.quad, sol.a)
        self.sol = sol
        #: small-signal reluctivity at the quadrature points, shape (n_el, n_qp, 2, 2), m/H
        self.nu_t = small_signal_tangent(d.materials, b0)
        _, ff = assemble_matrix(d.pattern, element_stiffness(d.quad, self.nu_t))
        self._lu = factorize(ff)

    def magnetisation_rhs(self, elements: np.ndarray, mu0_dm: np.ndarray) -> np.ndarray:
        """Load vector ∫ ν_t μ0 ΔM · B(v) r dr dz (per radian) of a magnetisation source.

        Parameters
        ----------
        elements : ndarray of int, shape (k,)
        mu0_dm : ndarray, shape (k, n_qp, 2)
            μ0 ΔM at the elements' quadrature points, T (per unit of the source's scale).

        Returns
        -------
        ndarray, shape (n_dofs,)
        """
        d = self.sol.disc
        q = d.quad
        src = np.einsum("eqcd,eqd->eqc", self.nu_t[elements], mu0_dm)
        fe = np.einsum("eqic,eqc->ei", q.g[elements], src * q.w[elements][..., None])
        return assemble_vector(q.dofs[:, elements], fe, d.basis.N)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Potentials of load vectors, A = 0 on the Dirichlet boundary.

        Parameters
        ----------
        rhs : ndarray, shape (n_src, n_dofs)

        Returns
        -------
        ndarray, shape (n_src, n_dofs)
            A_φ dofs, T m per unit source.
        """
        rhs = np.atleast_2d(rhs)
        free = self.sol.disc.pattern.free
        out = np.zeros_like(rhs, dtype=float)
        if free.size and rhs.shape[0]:
            out[:, free] = self._lu.solve(np.ascontiguousarray(rhs[:, free].T)).T
        return out

    def probe_kernel(self, probe: sp.csr_matrix, block: int = 200,
                     dtype: type = np.float64) -> np.ndarray:
        """P K_t⁻¹ Pᵀ of a probe matrix: the potential at probe point k of a unit load at
        probe point l (A = 0 on the Dirichlet boundary), shape (n, n).

        Solved in blocks of ``block`` right-hand sides on the free dofs only (no full-size
        temporaries).

        Parameters
        ----------
        probe : scipy.sparse.csr_matrix, shape (n, n_dofs)
            Values at the points from the dofs (:func:`msens.field.probes.p2_probes`).
        block : int
            Right-hand sides per solve.
        dtype : type
            Of the result (float32 halves its size).
        """
        free = self.sol.disc.pattern.free
        pf = sp.csr_matrix(probe[:, free])
        n = pf.shape[0]
        out = np.empty((n, n), dtype=dtype)
        for k in range(0, n, block):
            x = self._lu.solve(np.ascontiguousarray(pf[k:k + block].toarray().T))
            out[:, k:k + block] = pf @ x
        return out

    def solve_magnetisation(self, elements: np.ndarray, mu0_dm: np.ndarray) -> np.ndarray:
        """Dofs of the linearised field of one magnetisation source, shape (n_dofs,)."""
        return self.solve(self.magnetisation_rhs(elements, mu0_dm))[0]


def bias_residual(sol: FieldSolution, q, a: np.ndarray, shift: np.ndarray | None = None, *,
                  elements: np.ndarray | None = None) -> np.ndarray:
    """Residual ∫ (H(B − shift) − H_c e_z)·B(v) r (per radian) of the bias problem.

    Parameters
    ----------
    sol : FieldSolution
        Gives the materials, the dof count.
    q : QuadratureData
        Quadrature of the mesh (the bias mesh, or a morphed copy of it), or of the
        ``elements`` only.
    a : ndarray, shape (n_dofs,)
    shift : ndarray, shape (n_el, n_qp, 2), optional
        An added magnetisation μ0 ΔM at the quadrature points, T (H = H_law(B − μ0 ΔM)).
    elements : ndarray of int, optional
        The elements ``q`` covers (default: all): their part of the residual.

    Returns
    -------
    ndarray, shape (n_dofs,)
    """
    mat = sol.disc.materials if elements is None else sol.disc.materials.take(elements)
    b = flux_density_qp(q, a) if shift is None else flux_density_qp(q, a) - shift
    nu, _ = reluctivities(mat, b)
    return _residual_at(q, mat, b, nu, sol.basis.N)


def _residual_at(q, mat, b: np.ndarray, nu: np.ndarray, n: int) -> np.ndarray:
    """The residual of :func:`bias_residual` from the flux density and secant reluctivity at
    the quadrature points (shape (n_el, n_qp, 2) and (n_el, n_qp))."""
    h = nu[..., None] * b
    h[..., 1] -= mat.hc[:, None]
    return assemble_vector(q.dofs, np.einsum("eqic,eqc->ei", q.g, h * q.w[..., None]), n)


#: Relative Newton step below which :func:`nonlinear_resolve` keeps its factorised Jacobian
#: (chord steps: the Jacobian's change is of the order of the step, so each further step
#: shrinks about this much; a factorisation costs ~12 back-substitutions).
CHORD_BELOW = 1e-5


def nonlinear_resolve(sol: FieldSolution, q, shift: np.ndarray | None = None, *,
                      tol: float = 1e-12, max_iter: int = 20,
                      start: np.ndarray | None = None) -> np.ndarray:
    """Newton re-solve of the bias problem on quadrature ``q`` and with the magnetisation
    ``shift`` (see :func:`bias_residual`): the independent check of the linearised sources.
    Starts from the bias solution, or from ``start`` (dofs of a nearby state on the same
    mesh, shape (n_dofs,); its fixed dofs must be the bias solution's). Stops when the step
    is at most ``tol`` of the free dofs' norm; once a step is below :data:`CHORD_BELOW`, the
    last Jacobian is kept while the steps keep shrinking tenfold. Returns the dofs, shape
    (n_dofs,)."""
    d = sol.disc
    mat = d.materials
    free = d.pattern.free
    a = (sol.a if start is None else np.asarray(start, dtype=float)).copy()
    lu, last = None, np.inf
    for _ in range(max_iter):
        b = flux_density_qp(q, a) if shift is None else flux_density_qp(q, a) - shift
        nu, nu_d = reluctivities(mat, b)
        res = _residual_at(q, mat, b, nu, sol.basis.N)[free]
        if lu is None or last > CHORD_BELOW:
            _, ff = assemble_matrix(d.pattern, element_stiffness(q, tangent(b, nu, nu_d)))
            lu = factorize(ff)
        da = lu.solve(-res)
        a[free] += da
        step = np.linalg.norm(da) / max(np.linalg.norm(a[free]), 1e-300)
        if step <= tol:
            break
        # a chord step that did not shrink tenfold: the next one re-factorises
        lu = lu if step <= 0.1 * last else None
        last = step
    return a


def region_linkage(sol: FieldSolution, potentials: np.ndarray, region: str, turns: int,
                   area: float) -> np.ndarray:
    """(N/S) ∫_region 2π r A dS for each potential, exact mesh quadrature, Wb per unit.

    Parameters
    ----------
    sol : FieldSolution
        Gives the mesh, its subdomains and the quadrature.
    potentials : ndarray, shape (n, n_dofs) or (n_dofs,)
    region : str
        Mesh subdomain of the winding (``coil_<particle>``).
    turns : int
    area : float
        Winding cross-section S, m².

    Returns
    -------
    ndarray, shape (n,) (a float for one potential)
    """
    el = sol.problem.mesh.subdomains[region]
    q = sol.disc.quad
    pot = np.atleast_2d(potentials)
    a = np.einsum("eqi,nie->neq", q.phi[el], pot[:, q.dofs[:, el]])
    out = turns / area * TWO_PI * np.sum(a * q.w[el], axis=(1, 2))
    return out if np.ndim(potentials) == 2 else float(out[0])


def adjoint_linkage(h_coil: np.ndarray, elements: np.ndarray, mu0_dm: np.ndarray,
                    weights: np.ndarray) -> float:
    """μ0 ∫ h1 · ΔM dV over ``elements`` (the adjoint reading of reciprocity), Wb per unit.

    Parameters
    ----------
    h_coil : ndarray, shape (n_el, n_qp, 2)
        The coil's incremental H per ampere at every quadrature point, 1/m.
    elements : ndarray of int, shape (k,)
    mu0_dm : ndarray, shape (k, n_qp, 2)
        μ0 ΔM, T.
    weights : ndarray, shape (n_el, n_qp)
        Quadrature weights (r dr dz included), m³ per radian.
    """
    return TWO_PI * float(np.sum(np.einsum("eqc,eqc->eq", h_coil[elements], mu0_dm)
                                 * weights[elements]))


# ----------------------------------------------------------------------------- table

@dataclass(frozen=True)
class LinkageTable:
    """Summed-area table of f_s(r, z) = 2π r A_s(r, z) on a regular grid.

    Attributes
    ----------
    r, z : ndarray, shapes (nr,), (nz,)
        Grid lines, m.
    cumulative : ndarray, shape (n_sources, nr, nz)
        I_s(r_j, z_k) = ∫_{r_0}^{r_j} ∫_{z_0}^{z_k} f_s dz dr (trapezoidal), Wb per unit.
    """

    r: np.ndarray
    z: np.ndarray
    cumulative: np.ndarray


def _cumtrapz(f: np.ndarray, h: float, axis: int) -> np.ndarray:
    f = np.moveaxis(f, axis, -1)
    out = np.zeros_like(f)
    out[..., 1:] = np.cumsum(0.5 * h * (f[..., 1:] + f[..., :-1]), axis=-1)
    return np.moveaxis(out, -1, axis)


@dataclass(frozen=True)
class TableGrid:
    """The nodes of a linkage table and a field model's P2 evaluation matrix at them (built
    once when many potentials of one model are tabulated on one grid).

    Attributes
    ----------
    r, z : ndarray, shapes (nr,), (nz,)
        Grid lines, m.
    probe : scipy.sparse.csr_matrix, shape (nr * nz, n_dofs)
        A_φ at the nodes (r-major) from the dofs.
    """

    r: np.ndarray
    z: np.ndarray
    probe: sp.csr_matrix


def table_grid(sol: FieldSolution, r_range: tuple[float, float], z_range: tuple[float, float],
               spacing: float = 0.1e-3) -> TableGrid:
    """The grid of :func:`linkage_table` over a rectangle and its probe matrix."""
    (r0, r1), (z0, z1) = r_range, z_range
    internal(0 <= r0 < r1 and z0 < z1, f"internal: bad table ranges r {r_range}, z {z_range}")
    nr = max(2, int(np.ceil((r1 - r0) / spacing)) + 1)
    nz = max(2, int(np.ceil((z1 - z0) / spacing)) + 1)
    r = np.linspace(r0, r1, nr)
    z = np.linspace(z0, z1, nz)
    rr, zz = np.meshgrid(r, z, indexing="ij")
    return TableGrid(r=r, z=z, probe=p2_probes(sol.basis, rr.ravel(), zz.ravel()))


def tabulate(grid: TableGrid, potentials: np.ndarray) -> LinkageTable:
    """The summed-area table of ``potentials`` (shape (n_sources, n_dofs), real or complex)
    on ``grid``."""
    r, z = grid.r, grid.z
    a = (grid.probe @ potentials.T).T.reshape(len(potentials), r.size, z.size)
    f = TWO_PI * r[None, :, None] * a
    cum = _cumtrapz(_cumtrapz(f, r[1] - r[0], 1), z[1] - z[0], 2)
    return LinkageTable(r=r, z=z, cumulative=cum)


def linkage_table(sol: FieldSolution, potentials: np.ndarray, r_range: tuple[float, float],
                  z_range: tuple[float, float], spacing: float = 0.1e-3) -> LinkageTable:
    """Tabulate the potentials' flux per unit area over a rectangle of the (r, z) plane.

    Parameters
    ----------
    sol : FieldSolution
        Gives the mesh and basis of ``potentials``.
    potentials : ndarray, shape (n_sources, n_dofs)
    r_range, z_range : (float, float)
        Region every coil design lies in, m (inside the mesh).
    spacing : float
        Grid spacing, m (the rectangle integrals converge as spacing²).
    """
    return tabulate(table_grid(sol, r_range, z_range, spacing), potentials)


def _interp_weights(grid: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = grid[1] - grid[0]
    t = (np.asarray(x, dtype=float) - grid[0]) / h
    internal(bool(np.all((t >= -1e-9) & (t <= grid.size - 1 + 1e-9))),
             f"internal: coil edge outside the linkage table {grid[0]:.4g}..{grid[-1]:.4g} m")
    i = np.clip(np.floor(t).astype(int), 0, grid.size - 2)
    return i, np.clip(t - i, 0.0, 1.0)


def rect_integral(table: LinkageTable, r0: np.ndarray, r1: np.ndarray, z0: np.ndarray,
                  z1: np.ndarray) -> np.ndarray:
    """∫_{r0}^{r1} ∫_{z0}^{z1} 2π r A_s dz dr for many rectangles, shape (n_rect, n_sources).

    Bilinear interpolation of the summed-area table at the four corners.
    """
    c = table.cumulative

    def corner(rv, zv):
        i, u = _interp_weights(table.r, rv)
        j, v = _interp_weights(table.z, zv)
        return ((1 - u) * (1 - v) * c[:, i, j] + u * (1 - v) * c[:, i + 1, j]
                + (1 - u) * v * c[:, i, j + 1] + u * v * c[:, i + 1, j + 1]).T

    return corner(r1, z1) - corner(r0, z1) - corner(r1, z0) + corner(r0, z0)


__all__ = [
    "LinkageTable",
    "TableGrid",
    "TangentOperator",
    "adjoint_linkage",
    "bias_residual",
    "linkage_table",
    "nonlinear_resolve",
    "rect_integral",
    "region_linkage",
    "table_grid",
    "tabulate",
]
