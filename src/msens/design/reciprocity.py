"""Villari sensitivity of ANY coil from one bias solve: reciprocity used "the other way round".

The transducer's reciprocity (design.md §5) reads ΔΛ = μ0 ∫ h1 · ΔM dV with h1 the coil's
incremental field per ampere. Read the other way, ΔΛ is the flux linkage of the coil in the
field that the stress-induced magnetisation ΔM itself drives through the incremental
(linearised, bias-point) problem:

    K_t a_i = ∫ (ν_t μ0 ΔM_i) · B(v) r dr dz,        Λ_i(coil) = (N/S) ∫_coil 2π r a_i dS,

where K_t is the tangent stiffness at the bias point (the same operator as
:func:`msens.field.solve.incremental`; it is symmetric, so both readings agree to round-off:
tests/design/test_reciprocity.py). One factorisation and one right-hand side per bead give
potentials a_i; every coil design is then a rectangle integral of 2π r a_i, evaluated from
a summed-area table in O(1) per design.

Magnetoelastic source (as specified for the transducer, issue 4): the linear piezomagnetic law
at zero stress along the local bias field, μ0 ΔM = d(|H|) σ_eq ĥ, with d = (∂B/∂σ)_H from
:func:`msens.magnetoelastic.piezomagnetic_coefficient` (the contact stresses are GPa, beyond the
nonlinear law's range) and σ_eq the equivalent uniaxial stress along ĥ
(:func:`msens.magnetoelastic.equivalent_uniaxial_stress`) of a bead squeezed at both poles by
F_ref (:mod:`msens.beadstress`, sampled by :class:`msens.villari.StressSampler`), divided by
F_ref. F_ref is the static contact load that sets the
field model's contact flats, so stress field and flat geometry agree. A contact force loads both
beads it joins: ∂Λ/∂F_c = (S_i + S_{i+1})/2 (the bead-end and inertial load differences are
neglected, as in the transducer). The bead values S_i agree with
:func:`msens.villari.villari_sensitivities` (an independent implementation) to round-off.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import matplotlib.tri as mtri
import numpy as np
import scipy.sparse as sp

from msens.beadstress import BeadStress, solve_bead_stress
from msens.errors import require
from msens.field.assembly import assemble_matrix, factorize
from msens.field.constitutive import reluctivities, tangent
from msens.field.forms import element_stiffness, flux_density_qp
from msens.field.geometry import SensorGeometry
from msens.field.solve import FieldSolution, internal_field_strength
from msens.magnetoelastic import (
    JilesAthertonSablik,
    equivalent_uniaxial_stress,
    piezomagnetic_coefficient,
)
from msens.materials import BEAD_STEEL
from msens.steel_law import law_for_steel
from msens.units import TWO_PI
from msens.villari import StressSampler


def bead_stress(geometry: SensorGeometry) -> BeadStress:
    """Stress field of a bead at the geometry's contact load F_ref (both poles)."""
    b = geometry.beads
    return solve_bead_stress(b.radius, BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio,
                             b.contact_load)


def villari_sources(bias: FieldSolution, geometry: SensorGeometry, particles: Sequence[int],
                    *, law: JilesAthertonSablik | None = None,
                    stress: BeadStress | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """μ0 ΔM per newton of a symmetric two-pole load, in each bead's elements.

    Parameters
    ----------
    bias : FieldSolution
        Nonlinear bias state.
    geometry : SensorGeometry
    particles : sequence of int
        Beads (each a mesh subdomain ``bead_<p>``).
    law : JilesAthertonSablik, optional
        Magnetoelastic law of the bead steel; default :func:`msens.steel_law.law_for_steel`
        of the geometry's B–H table.
    stress : BeadStress, optional
        Bead stress at F_ref (default :func:`bead_stress`).

    Returns
    -------
    list of (elements, source)
        Per bead: element indices, shape (n_e,), and μ0 ΔM / F at their quadrature points,
        shape (n_e, n_qp, 2), T/N.
    """
    stress = stress or bead_stress(geometry)
    law = law_for_steel(geometry.steel) if law is None else law
    sampler = StressSampler(stress)  # the transducer's fast point location, stress per N
    axi = bias.problem.mesh
    xq = np.asarray(bias.basis.global_coordinates())  # (2, n_el, n_qp)
    h_all = internal_field_strength(bias)
    out = []
    for p in particles:
        el = axi.subdomains[f"bead_{p}"]
        r = xq[0, el]
        z = xq[1, el] - geometry.beads.center(p)
        # mesh points of a truncated bead lie inside its sphere up to round-off
        rho = np.hypot(r, z)
        scale = np.minimum(1.0, stress.radius / np.where(rho > 0, rho, 1.0))
        sig = sampler(r * scale, z * scale)
        h = h_all[el]
        hmag = np.sqrt(np.sum(h**2, axis=-1))
        hhat = h / np.where(hmag > 0, hmag, 1.0)[..., None]
        d = piezomagnetic_coefficient(law, hmag)
        s_eq = equivalent_uniaxial_stress(sig, hhat)
        out.append((el, (d * s_eq)[..., None] * hhat))
    return out


def _tangent_operator(bias: FieldSolution):
    d = bias.disc
    b = flux_density_qp(d.quad, bias.a)
    nu, nu_d = reluctivities(d.materials, b)
    nu_t = tangent(b, nu, nu_d)
    _, ff = assemble_matrix(d.pattern, element_stiffness(d.quad, nu_t))
    return nu_t, factorize(ff)


def source_potentials(bias: FieldSolution,
                      sources: Sequence[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Incremental potentials driven by magnetisation sources, one factorisation.

    Parameters
    ----------
    bias : FieldSolution
    sources : sequence of (elements, mu0_dM)
        As returned by :func:`villari_sources`.

    Returns
    -------
    ndarray, shape (n_sources, n_dofs)
        A_φ dofs per unit source (T m per N for Villari sources).
    """
    d = bias.disc
    nu_t, lu = _tangent_operator(bias)
    free = d.pattern.free
    rhs = np.zeros((free.size, len(sources)))
    for k, (el, m) in enumerate(sources):
        s = np.einsum("eqcd,eqd->eqc", nu_t[el], m)
        fe = np.einsum("eqic,eqc->ei", d.quad.g[el], s * d.quad.w[el][..., None])
        full = np.zeros(d.basis.N)
        np.add.at(full, d.quad.dofs[:, el].T, fe)
        rhs[:, k] = full[free]
    out = np.zeros((len(sources), d.basis.N))
    if free.size:
        out[:, free] = lu.solve(rhs).T
    return out


def direct_linkage(h1: FieldSolution, sources: Sequence[tuple[np.ndarray, np.ndarray]]
                   ) -> np.ndarray:
    """μ0 ∫ h1 · ΔM dV per source (the transducer's reading of reciprocity), Wb per unit.

    Parameters
    ----------
    h1 : FieldSolution
        Incremental solution of the coil at 1 A (``incremental(bias, {coil: N/S})``).
    sources : sequence of (elements, mu0_dM)
    """
    h = internal_field_strength(h1)
    w = h1.disc.quad.w
    return np.array([TWO_PI * float(np.sum(np.sum(h[el] * m, axis=-1) * w[el]))
                     for el, m in sources])


def region_linkage(bias: FieldSolution, potentials: np.ndarray, region: str, turns: int,
                   area: float) -> np.ndarray:
    """(N/S) ∫_region 2π r A dS for each potential, exact mesh quadrature, shape (n,)."""
    el = bias.problem.mesh.subdomains[region]
    q = bias.disc.quad
    a = np.einsum("eqi,nie->neq", q.phi[el], potentials[:, q.dofs[:, el]])
    return turns / area * TWO_PI * np.sum(a * q.w[el], axis=(1, 2))


# ----------------------------------------------------------------------------- table

@dataclass(frozen=True)
class LinkageTable:
    """Summed-area table of f_i(r, z) = 2π r A_i(r, z) on a regular grid.

    Attributes
    ----------
    r, z : ndarray, shapes (nr,), (nz,)
        Grid lines, m.
    cumulative : ndarray, shape (n_sources, nr, nz)
        I_i(r_j, z_k) = ∫_{r_0}^{r_j} ∫_{z_0}^{z_k} f_i dz dr (trapezoidal), Wb per unit.
    """

    r: np.ndarray
    z: np.ndarray
    cumulative: np.ndarray


def _cumtrapz(f: np.ndarray, h: float, axis: int) -> np.ndarray:
    f = np.moveaxis(f, axis, -1)
    out = np.zeros_like(f)
    out[..., 1:] = np.cumsum(0.5 * h * (f[..., 1:] + f[..., :-1]), axis=-1)
    return np.moveaxis(out, -1, axis)


def linkage_table(bias: FieldSolution, potentials: np.ndarray, r_range: tuple[float, float],
                  z_range: tuple[float, float], spacing: float = 0.1e-3) -> LinkageTable:
    """Tabulate the potentials' flux per unit area over a rectangle of the (r, z) plane.

    Parameters
    ----------
    bias : FieldSolution
        Gives the mesh and basis of ``potentials``.
    potentials : ndarray, shape (n_sources, n_dofs)
    r_range, z_range : (float, float)
        Region every coil design lies in, m (inside the mesh).
    spacing : float
        Grid spacing, m (the rectangle integrals converge as spacing²).
    """
    (r0, r1), (z0, z1) = r_range, z_range
    require(0 <= r0 < r1 and z0 < z1, f"bad table ranges r {r_range}, z {z_range}")
    nr = max(2, int(np.ceil((r1 - r0) / spacing)) + 1)
    nz = max(2, int(np.ceil((z1 - z0) / spacing)) + 1)
    r = np.linspace(r0, r1, nr)
    z = np.linspace(z0, z1, nz)
    rr, zz = np.meshgrid(r, z, indexing="ij")
    probe = p2_probes(bias.basis, rr.ravel(), zz.ravel())
    a = (probe @ potentials.T).T.reshape(len(potentials), nr, nz)
    f = TWO_PI * rr[None] * a
    cum = _cumtrapz(_cumtrapz(f, r[1] - r[0], 1), z[1] - z[0], 2)
    return LinkageTable(r=r, z=z, cumulative=cum)


def p2_probes(basis, r: np.ndarray, z: np.ndarray) -> sp.csr_matrix:
    """Sparse evaluation matrix of a P2 field on straight triangles at points, (n_pts, N).

    Point location by matplotlib's trapezoid-map finder (fast for many points, unlike a
    per-point mapping inversion); P2 shape functions in barycentric coordinates λ:
    λ_i(2λ_i − 1) at the vertices, 4 λ_i λ_j on the edges (0,1), (1,2), (0,2) — scikit-fem's
    local dof order for ElementTriP2 (checked against ``basis.probes`` in the tests).
    """
    mesh = basis.mesh
    tri = mtri.Triangulation(mesh.p[0], mesh.p[1], mesh.t.T)
    e = tri.get_trifinder()(r, z)
    require(bool(np.all(e >= 0)), "p2_probes: points outside the mesh")
    p0, p1, p2 = (mesh.p[:, mesh.t[k, e]] for k in range(3))
    det = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1])
    l1 = ((r - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (z - p0[1])) / det
    l2 = ((p1[0] - p0[0]) * (z - p0[1]) - (r - p0[0]) * (p1[1] - p0[1])) / det
    l0 = 1.0 - l1 - l2
    shape = np.stack([l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1),
                      4 * l0 * l1, 4 * l1 * l2, 4 * l0 * l2])
    rows = np.broadcast_to(np.arange(r.size), shape.shape)
    return sp.csr_matrix((shape.ravel(), (rows.ravel(), basis.element_dofs[:, e].ravel())),
                         shape=(r.size, basis.N))


def _interp_weights(grid: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = grid[1] - grid[0]
    t = (np.asarray(x, dtype=float) - grid[0]) / h
    require(bool(np.all((t >= -1e-9) & (t <= grid.size - 1 + 1e-9))),
            f"coil edge outside the linkage table {grid[0]:.4g}..{grid[-1]:.4g} m")
    i = np.clip(np.floor(t).astype(int), 0, grid.size - 2)
    return i, np.clip(t - i, 0.0, 1.0)


def rect_integral(table: LinkageTable, r0: np.ndarray, r1: np.ndarray, z0: np.ndarray,
                  z1: np.ndarray) -> np.ndarray:
    """∫_{r0}^{r1} ∫_{z0}^{z1} 2π r A_i dz dr for many rectangles, shape (n_rect, n_sources).

    Bilinear interpolation of the summed-area table at the four corners.
    """
    c = table.cumulative

    def corner(rv, zv):
        i, u = _interp_weights(table.r, rv)
        j, v = _interp_weights(table.z, zv)
        return ((1 - u) * (1 - v) * c[:, i, j] + u * (1 - v) * c[:, i + 1, j]
                + (1 - u) * v * c[:, i, j + 1] + u * v * c[:, i + 1, j + 1]).T

    return corner(r1, z1) - corner(r0, z1) - corner(r1, z0) + corner(r0, z0)


def contact_sensitivities(bead_values: np.ndarray) -> np.ndarray:
    """∂Λ/∂F_c = (S_i + S_{i+1})/2 for consecutive beads, shape (..., n_beads - 1)."""
    return 0.5 * (bead_values[..., :-1] + bead_values[..., 1:])


__all__ = ["LinkageTable", "bead_stress", "contact_sensitivities", "direct_linkage",
           "linkage_table", "rect_integral", "region_linkage", "source_potentials",
           "villari_sources"]
