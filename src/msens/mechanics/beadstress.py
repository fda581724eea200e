"""Stress in a bead squeezed between its two neighbours (axisymmetric linear elasticity).

A sphere of radius R is pressed by two equal and opposite forces F along its axis z, each
transmitted through a Hertz contact: on a cap of radius a around each pole the surface carries
the pressure p(rho) = p0 sqrt(1 - rho^2/a^2) (Johnson 1985, *Contact Mechanics*, §4.2,
eqs. 4.22-4.24):

    a = (3 F R* / (4 E*))^(1/3),   p0 = 3 F / (2 pi a^2),
    R* = R/2 (two equal spheres),   E* = E / (2 (1 - nu^2)) (same material).

The pressure acts along the axis, per unit area projected on the plane z = const: between two
frictionless spheres the deformed contact surface is that plane, so the traction on it is
purely axial, and the load resultant is exactly F.

By symmetry about the equator only the upper quarter of the meridian section is solved, with
u_z = 0 on z = 0 (which also removes the axial rigid motion) and u_r = 0 on the axis. The
weak form is the axisymmetric one: strains (d_r u_r, d_z u_z, u_r/r, d_z u_r + d_r u_z) and
every integral weighted by r. Elements are quadratic (P2) on a curved quadratic mesh graded
toward the contact.

Linearity in F. For a fixed contact radius the problem is linear, but a grows as F^(1/3), so
the stress *near the contact* (within a few a of the pole) is not proportional to F: p0 grows
as F^(1/3). The bead-average stress is exactly linear: by the mean-stress theorem
<sigma_ij> = (1/V) * (surface integral of x_i t_j), which for axial tractions at z = +-R gives
<sigma_zz> = -2 F R / V = -3 F / (2 pi R^2) and <sigma_rr> = <sigma_thth> = <sigma_rz> = 0,
whatever a is (up to a relative O(a^2/R^2) from the cap's curvature). Far from the contacts
(Saint-Venant) the field depends on F only, to the same order. A solution is therefore for one
force; ``stress_at(bs, ...) / bs.force`` is the stress per newton at that force
(:mod:`msens.mechanics.stress_sampling`; the elasticity solver is
:mod:`msens.mechanics.elasticity`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import skfem
from skfem import Functional

from msens.errors import require
from msens.mechanics.beadmesh import BeadMeshSpec, bead_section_mesh
from msens.mechanics.elasticity import _project_stress, lame_parameters, solve_traction
from msens.mechanics.hertz import hertz_contact_radius, identical_spheres_modulus

#: Component order of every stress array returned here.
COMPONENTS = ("rr", "zz", "tt", "rz")


def hertz_contact(radius: float, youngs_modulus: float, poisson_ratio: float,
                  force: float) -> tuple[float, float]:
    """Contact radius and peak pressure of two equal elastic spheres pressed together.

    Parameters
    ----------
    radius : float
        Sphere radius R, m (both spheres).
    youngs_modulus : float
        E, Pa (both spheres).
    poisson_ratio : float
        nu (both spheres).
    force : float
        Contact force F, N, > 0.

    Returns
    -------
    a : float
        Contact radius, m: a = (3 F R* / (4 E*))^(1/3), R* = R/2, E* = E / (2 (1 - nu^2)).
    p0 : float
        Peak (central) pressure, Pa: p0 = 3 F / (2 pi a^2).

    References
    ----------
    K. L. Johnson, *Contact Mechanics*, Cambridge University Press (1985), §4.2.
    """
    _check_material(radius, youngs_modulus, poisson_ratio)
    require(np.isfinite(force) and force > 0, f"force must be > 0 N, got {force}")
    e_eff = identical_spheres_modulus(youngs_modulus, poisson_ratio)
    a = float(hertz_contact_radius(force, radius / 2.0, e_eff))
    return a, 3.0 * force / (2.0 * np.pi * a**2)


def hertz_axis_stress(depth: np.ndarray, contact_radius: float, peak_pressure: float,
                      poisson_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Hertz half-space stress on the load axis below a circular contact.

    Parameters
    ----------
    depth : ndarray, shape (n,)
        Depth below the surface, m, >= 0.
    contact_radius, peak_pressure : float
        a (m) and p0 (Pa), e.g. from :func:`hertz_contact`.
    poisson_ratio : float
        nu.

    Returns
    -------
    sigma_zz, sigma_rr : ndarray, shape (n,)
        Axial and radial (= hoop) stress on the axis, Pa (compression negative).

    References
    ----------
    K. L. Johnson, *Contact Mechanics* (1985), eq. (3.45).
    """
    zeta = np.asarray(depth, dtype=float) / contact_radius
    with np.errstate(divide="ignore", invalid="ignore"):
        atan_term = np.where(zeta > 0, zeta * np.arctan2(1.0, zeta), 0.0)
    s_zz = -peak_pressure / (1.0 + zeta**2)
    s_rr = peak_pressure * (-(1.0 + poisson_ratio) * (1.0 - atan_term)
                            + 0.5 / (1.0 + zeta**2))
    return s_zz, s_rr


@dataclass(frozen=True)
class BeadStress:
    """Solved stress field of a bead under two opposite Hertz contact loads.

    Attributes
    ----------
    radius : float
        Bead radius R, m.
    youngs_modulus : float
        E, Pa.
    poisson_ratio : float
        nu.
    force : float
        Contact force F at each pole, N (compressive).
    contact_radius : float
        Hertz contact radius a at this force, m.
    peak_pressure : float
        Hertz peak pressure p0 at this force, Pa.
    basis : skfem.CellBasis
        P2 vector basis on the quarter section, mesh coordinates (r, s) in m with
        s = z - R (see :mod:`msens.mechanics.beadmesh`); components (u_r, u_z).
    displacement : ndarray, shape (basis.N,)
        Displacement dofs, m.
    stress_basis : skfem.CellBasis
        Discontinuous P2 scalar basis carrying the stress components.
    stress_dofs : ndarray, shape (4, stress_basis.N)
        Element-wise L2 projection of (sigma_rr, sigma_zz, sigma_thth, sigma_rz), Pa.
    spec : BeadMeshSpec
        Mesh sizes used.
    """

    radius: float
    youngs_modulus: float
    poisson_ratio: float
    force: float
    contact_radius: float
    peak_pressure: float
    basis: skfem.CellBasis
    displacement: np.ndarray
    stress_basis: skfem.CellBasis
    stress_dofs: np.ndarray
    spec: BeadMeshSpec

    @property
    def ndofs(self) -> int:
        """Number of displacement unknowns (before constraints)."""
        return int(self.basis.N)


def _check_material(radius: float, youngs_modulus: float, poisson_ratio: float) -> None:
    require(np.isfinite(radius) and radius > 0, f"radius must be > 0 m, got {radius}")
    require(np.isfinite(youngs_modulus) and youngs_modulus > 0,
            f"youngs_modulus must be > 0 Pa, got {youngs_modulus}")
    require(-1.0 < poisson_ratio < 0.5,
            f"poisson_ratio must be in (-1, 0.5), got {poisson_ratio}")


def solve_bead_stress(radius: float, youngs_modulus: float, poisson_ratio: float,
                      force: float, *, refine: int = 0,
                      spec: BeadMeshSpec | None = None) -> BeadStress:
    """Solve for the stress in a bead squeezed by two opposite Hertz contacts.

    Parameters
    ----------
    radius : float
        Bead radius R, m (4.76 mm beads: 2.38e-3).
    youngs_modulus : float
        E, Pa.
    poisson_ratio : float
        nu.
    force : float
        Contact force F at each pole, N, > 0.
    refine : int, optional
        Uniform refinement level (all element sizes divided by 2**refine); ignored if
        ``spec`` is given.
    spec : BeadMeshSpec, optional
        Full mesh specification.

    Returns
    -------
    BeadStress

    Notes
    -----
    Gauss quadrature of sqrt(1 - rho^2/a^2), whose slope is infinite at the contact edge
    (a mesh node), makes the discrete load resultant err by O((h/a)^1.5) (1.7e-4 on the
    default mesh). The pressure is therefore rescaled so that the discrete resultant is
    exactly F; the mean stress then converges at the O(h^4) rate of the curved geometry.
    """
    _check_material(radius, youngs_modulus, poisson_ratio)
    a, p0 = hertz_contact(radius, youngs_modulus, poisson_ratio, force)
    spec = spec or BeadMeshSpec(refine=refine)
    mesh = bead_section_mesh(radius, a, spec)
    facets = mesh.boundaries["contact"]
    scale = force / hertz_resultant(mesh, facets, a, p0)

    def hertz(rho, s, n_r, n_z):
        p = scale * p0 * np.sqrt(np.clip(1.0 - (rho / a) ** 2, 0.0, None))
        return np.zeros_like(p), -p * np.abs(n_z)  # axial, per projected area

    basis, u = solve_traction(mesh, youngs_modulus, poisson_ratio, hertz, facets,
                              intorder=_HERTZ_INTORDER)
    lam, mu = lame_parameters(youngs_modulus, poisson_ratio)
    sbasis = skfem.Basis(mesh, skfem.ElementDG(skfem.ElementTriP2()), intorder=6)
    sdofs = _project_stress(basis, sbasis, u, lam, mu)
    return BeadStress(radius=radius, youngs_modulus=youngs_modulus,
                      poisson_ratio=poisson_ratio, force=force, contact_radius=a,
                      peak_pressure=p0, basis=basis, displacement=u, stress_basis=sbasis,
                      stress_dofs=sdofs, spec=spec)


#: Facet quadrature order for the Hertz pressure (a high order reduces, but cannot remove,
#: the error of the square-root edge; see solve_bead_stress Notes).
_HERTZ_INTORDER = 12


def hertz_resultant(mesh: skfem.Mesh, facets: np.ndarray, contact_radius: float,
                    peak_pressure: float) -> float:
    """Axial resultant (N) of the Hertz pressure as integrated by the facet quadrature.

    Parameters
    ----------
    mesh : skfem.Mesh
        Section mesh, (r, s) in m.
    facets : ndarray of int
        Contact facets.
    contact_radius, peak_pressure : float
        a (m) and p0 (Pa).

    Returns
    -------
    float
        2 pi * integral of p(rho) |n_z| rho ds over the facets, N; exactly
        2 pi a^2 p0 / 3 = F.
    """
    fb = skfem.FacetBasis(mesh, skfem.ElementTriP2(), facets=facets,
                          intorder=_HERTZ_INTORDER)

    @Functional
    def resultant(w):
        rho = w.x[0]
        p = peak_pressure * np.sqrt(np.clip(1.0 - (rho / contact_radius) ** 2, 0.0, None))
        return 2 * np.pi * p * np.abs(w.n[1]) * rho

    return float(resultant.assemble(fb))
