"""Post-processing of axisymmetric field solutions: point fields, flux linkage, energy, force.

All integrals are over the body of revolution (the 2π is included). Forces are axial (the
radial resultant of an axisymmetric field vanishes).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Literal

import numpy as np
import scipy.sparse as sp
import skfem
from numpy.typing import ArrayLike
from scipy.sparse.linalg import spsolve

from msens.errors import InputError, require
from msens.field.constitutive import energy_density, reluctivities, small_signal_tangent
from msens.field.forms import flux_density_qp, potential_qp
from msens.field.mesh import AxiMesh
from msens.field.regions import Air, CurrentRegion
from msens.field.solve import FieldSolution, solve
from msens.params.units import MU0

__all__ = ["eggshell", "energy", "field_strength", "flux_density",
           "flux_linkage", "force_z", "potential_energy"]

TWO_PI = 2.0 * np.pi


def _points(r: ArrayLike, z: ArrayLike) -> tuple[np.ndarray, tuple[int, ...]]:
    r, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(z, dtype=float))
    require(bool(np.all(r >= 0)), "field points must have r >= 0")
    return np.vstack([r.ravel(), z.ravel()]), r.shape


def _evaluate(sol: FieldSolution, a: np.ndarray, pts: np.ndarray):
    """A, ∂A/∂r, ∂A/∂z at points (shape (2, n)) and the containing elements."""
    basis = sol.basis
    try:
        cells = basis.mesh.element_finder(mapping=basis.mapping)(pts[0], pts[1])
    except ValueError as exc:
        raise InputError(f"some field points are outside the mesh: {exc}") from exc
    loc = basis.mapping.invF(pts[:, :, None], tind=cells)
    val = np.zeros(pts.shape[1])
    grd = np.zeros((2, pts.shape[1]))
    for k in range(basis.Nbfun):
        f = basis.elem.gbasis(basis.mapping, loc, k, tind=cells)[0]
        coef = a[basis.element_dofs[k, cells]]
        val += coef * np.asarray(f)[:, 0]
        grd += coef * f.grad[:, :, 0]
    return val, grd, cells


def _b_from(val: np.ndarray, grd: np.ndarray, r: np.ndarray, scale: float) -> np.ndarray:
    # On the axis A = 0 and A/r -> dA/dr, so B_z = 2 dA/dr there.
    on_axis = r <= 1e-12 * scale
    a_over_r = np.where(on_axis, grd[0], val / np.where(on_axis, 1.0, r))
    return np.stack([-grd[1], grd[0] + a_over_r], axis=-1)


def flux_density(sol: FieldSolution, r: ArrayLike, z: ArrayLike) -> np.ndarray:
    """Flux density B = (B_r, B_z) at points, T.

    Parameters
    ----------
    sol : FieldSolution
    r, z : array_like
        Point coordinates, m (broadcast together; r >= 0, inside the mesh).

    Returns
    -------
    ndarray, shape (..., 2)
    """
    pts, shape = _points(r, z)
    val, grd, _ = _evaluate(sol, sol.a, pts)
    scale = float(np.ptp(sol.basis.mesh.p))
    return _b_from(val, grd, pts[0], scale).reshape(*shape, 2)


def field_strength(sol: FieldSolution, r: ArrayLike, z: ArrayLike) -> np.ndarray:
    """Field strength H = (H_r, H_z) at points, A/m, shape (..., 2).

    On an interface the element found first decides the material. For an incremental
    solution H = (dH/dB at the bias point) · B.
    """
    pts, shape = _points(r, z)
    scale = float(np.ptp(sol.basis.mesh.p))
    val, grd, cells = _evaluate(sol, sol.a, pts)
    b = _b_from(val, grd, pts[0], scale)[:, None, :]  # (n, 1, 2) like quadrature data
    if sol.bias is not None:
        bv, bg, _ = _evaluate(sol.bias, sol.bias.a, pts)
        bb = _b_from(bv, bg, pts[0], scale)[:, None, :]
        mat = _cell_materials(sol.bias, cells)
        return np.einsum("nqcd,nqd->nqc", small_signal_tangent(mat, bb), b)[:, 0].reshape(*shape, 2)
    mat = _cell_materials(sol, cells)
    nu, _ = reluctivities(mat, b)
    h = nu[..., None] * b
    h[..., 1] -= mat.hc[:, None]
    return h[:, 0].reshape(*shape, 2)


def _cell_materials(sol: FieldSolution, cells: np.ndarray):
    """Material fields restricted to (possibly repeated) ``cells``."""
    m = sol.disc.materials
    soft = tuple((np.flatnonzero(np.isin(cells, el)), law) for el, law in m.soft)
    return replace(m, nu=m.nu[cells], hc=m.hc[cells], br=m.br[cells], j=m.j[cells],
                   soft=soft)


def _region_elements(sol: FieldSolution, names: Sequence[str]) -> np.ndarray:
    subs = sol.problem.mesh.subdomains
    for n in names:
        require(n in subs, f"'{n}' is not a subdomain of the mesh (have {sorted(subs)})")
    return np.concatenate([subs[n] for n in names])


def flux_linkage(sol: FieldSolution, coil: str, turns: int) -> float:
    """Flux linkage of a homogenised coil, Λ = (N/S) ∫_coil 2π r A_φ dS, Wb.

    Parameters
    ----------
    coil : str
        Subdomain of the winding cross-section (area S).
    turns : int
        N, turns of the coil.
    """
    require(turns > 0, f"turns must be > 0, got {turns}")
    el = _region_elements(sol, [coil])
    q = sol.disc.quad
    a_qp = potential_qp(q, sol.a)
    area = float(np.sum(q.w[el] / q.r[el]))
    return float(turns / area * TWO_PI * np.sum(q.w[el] * a_qp[el]))


def energy(sol: FieldSolution) -> float:
    """Stored magnetic energy ∫ w(B) dV, J.

    w = ∫_0^B H·dB' in air, windings, linear and nonlinear soft parts; in magnets the
    recoil-line energy ``|B − B_r|²/(2 μ0 μ_rec)``. For an incremental solution the quadratic
    small-signal energy ½ B·(dH/dB)·B. For a linear current-driven problem energy = ½ L I².
    """
    q = sol.disc.quad
    b = flux_density_qp(q, sol.a)
    if sol.bias is not None:
        bb = flux_density_qp(q, sol.bias.a)
        w = 0.5 * np.einsum("eqc,eqcd,eqd->eq", b, small_signal_tangent(
            sol.bias.disc.materials, bb), b)
    else:
        nu, _ = reluctivities(sol.disc.materials, b)
        w = energy_density(sol.disc.materials, b, nu)
    return float(TWO_PI * np.sum(w * q.w))


def potential_energy(sol: FieldSolution) -> float:
    """The functional the solution minimises, Π = ∫ w(B) dV − ∫ J_φ A_φ dV, J.

    At the solution Π = −(co-energy) up to a constant, so the force on a rigidly moving body
    at fixed currents and remanence is F = −dΠ/dx.
    """
    q = sol.disc.quad
    a_qp = potential_qp(q, sol.a)
    source = TWO_PI * np.sum(sol.disc.materials.j[:, None] * a_qp * q.w)
    return energy(sol) - float(source)


def eggshell(mesh: AxiMesh, regions: dict, bodies: Sequence[str],
             outer: Sequence[str]) -> np.ndarray:
    """The eggshell function φ: P1, 1 on the bodies, 0 on every other non-air part and outer.

    In the air (regions of kind :class:`Air`) φ is the harmonic extension of those values
    (a 2-D Laplace solve), smooth across the whole air shell.

    Returns
    -------
    ndarray, shape (n_vertices,)
    """
    m = mesh.mesh
    for n in bodies:
        require(n in mesh.subdomains, f"body '{n}' is not a subdomain")
        require(not isinstance(regions[n], Air), f"body '{n}' is air; give magnetic parts")
    air = np.concatenate([mesh.subdomains[n] for n, r in regions.items()
                          if isinstance(r, Air) and n not in bodies])
    others = [n for n, r in regions.items() if n not in bodies and not isinstance(r, Air)]
    one = np.unique(m.t[:, np.concatenate([mesh.subdomains[n] for n in bodies])])
    zero = [m.facets[:, np.concatenate([mesh.boundaries[n] for n in outer])].ravel()]
    zero += [m.t[:, mesh.subdomains[n]].ravel() for n in others]
    zero = np.unique(np.concatenate(zero))
    clash = np.intersect1d(one, zero)
    if clash.size:
        touching = [n for n in others if np.intersect1d(m.t[:, mesh.subdomains[n]], one).size]
        raise InputError(f"bodies {list(bodies)} touch non-air parts {touching} (or the outer "
                         "boundary); force needs an air gap around the moving bodies")
    basis = skfem.CellBasis(m, skfem.ElementTriP1(), elements=air)
    k = skfem.asm(_laplace, basis)
    phi = np.zeros(m.p.shape[1])
    phi[one] = 1.0
    in_air = np.zeros(m.p.shape[1], dtype=bool)
    in_air[m.t[:, air].ravel()] = True
    fixed = np.zeros_like(in_air)
    fixed[one] = fixed[zero] = True
    free = np.flatnonzero(in_air & ~fixed)
    if free.size:
        rhs = -(k @ phi)[free]
        phi[free] = spsolve(sp.csc_matrix(k[free][:, free]), rhs)
    return phi


@skfem.BilinearForm
def _laplace(u, v, _):
    return u.grad[0] * v.grad[0] + u.grad[1] * v.grad[1]


def _p1_gradients(m: skfem.MeshTri, phi: np.ndarray) -> np.ndarray:
    """Constant gradient of a P1 vertex field per triangle, shape (n_elements, 2)."""
    p, t = m.p, m.t
    x1, x2, x3 = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    d1, d2 = x2 - x1, x3 - x1
    det = d1[0] * d2[1] - d1[1] * d2[0]
    f1, f2 = phi[t[1]] - phi[t[0]], phi[t[2]] - phi[t[0]]
    gx = (f1 * d2[1] - f2 * d1[1]) / det
    gy = (f2 * d1[0] - f1 * d2[0]) / det
    return np.stack([gx, gy], axis=-1)


def _force_maxwell(sol: FieldSolution, phi: np.ndarray) -> float:
    q = sol.disc.quad
    g = _p1_gradients(sol.problem.mesh.mesh, phi)
    active = np.flatnonzero(np.any(g != 0.0, axis=1))
    b = flux_density_qp(q, sol.a)[active]
    br, bz = b[..., 0], b[..., 1]
    # F_z = -∫ T_zj ∂_j φ dV, T = (B B - |B|²/2 I)/μ0 (air only, where ∇φ ≠ 0)
    t_zr = br * bz / MU0
    t_zz = 0.5 * (bz**2 - br**2) / MU0
    integrand = t_zr * g[active, 0][:, None] + t_zz * g[active, 1][:, None]
    return float(-TWO_PI * np.sum(integrand * q.w[active]))


def _force_virtual_work(sol: FieldSolution, phi: np.ndarray, step: float | None) -> float:
    prob = sol.problem
    m = prob.mesh.mesh
    g = _p1_gradients(m, phi)
    if step is None:
        # keep the deformation gradient within 1e-3 of the identity
        step = 1e-3 / float(np.max(np.hypot(g[:, 0], g[:, 1])))
    energies = []
    for s in (+1.0, -1.0):
        p = m.p.copy()
        p[1] += s * step * phi
        moved = skfem.MeshTri(p, m.t, _subdomains=dict(prob.mesh.subdomains),
                              _boundaries=dict(prob.mesh.boundaries) or None)
        mesh = replace(prob.mesh, mesh=moved)
        # Π is stationary at the solution, so its error is quadratic in the residual: 1e-10 is ample
        shifted = solve(replace(prob, mesh=mesh), initial=sol.a, tol=1e-10, max_iter=30)
        energies.append(potential_energy(shifted))
    return float(-(energies[0] - energies[1]) / (2.0 * step))


def force_z(sol: FieldSolution, bodies: Sequence[str], *,
            method: Literal["maxwell", "virtual_work"] = "maxwell",
            step: float | None = None) -> float:
    """Axial magnetic force on the union of the named subdomains, N (+ along +z).

    Parameters
    ----------
    sol : FieldSolution
        A bias solution (not an incremental one).
    bodies : sequence of str
        Subdomains moving together; they must be surrounded by air (regions of kind
        :class:`Air`) separating them from every other non-air part.
    method : {"maxwell", "virtual_work"}
        ``"maxwell"``: eggshell Maxwell stress F_z = −∫_air T_zj ∂_jφ dV with φ from
        :func:`eggshell`. ``"virtual_work"``: central difference of the minimised functional
        Π (:func:`potential_energy`) between two re-solved problems whose meshes are shifted
        by ±``step`` φ e_z (bodies moved rigidly, air deformed): F = −dΠ/dz.
    step : float, optional
        Virtual displacement for ``"virtual_work"``, m (default: 1e-3 / max|∇φ|).
    """
    require(sol.bias is None, "force_z needs a bias solution, not an incremental one")
    require(method in ("maxwell", "virtual_work"),
            f"method must be 'maxwell' or 'virtual_work', got '{method}'")
    require(len(bodies) > 0, "force_z needs at least one body")
    prob = sol.problem
    for n in bodies:
        require(n in prob.regions, f"body '{n}' is not a region of the problem")
        require(not isinstance(prob.regions[n], CurrentRegion),
                f"body '{n}' is a winding; windings are not supported as moving bodies")
    phi = eggshell(prob.mesh, dict(prob.regions), bodies, prob.outer)
    if method == "maxwell":
        return _force_maxwell(sol, phi)
    return _force_virtual_work(sol, phi, step)

