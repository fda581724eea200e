"""Contact-approach mechanism: the beads above a contact moving toward the wall.

When a contact is squeezed, the two beads approach by δ (Hertz: F = A δ^{3/2}) and the
contact's flat grows. In the truncated-sphere model the air gap outside the flat is
g(r) = (r² - a²)/R, so growing the flat by δa closes the whole wedge by 2a δa/R: to first
order the flat's growth *is* the approach (the sliver the rim sweeps is O(δa²)). The
mechanism is therefore the change of the bias field when every bead above contact c moves
rigidly toward the wall by δ_c (coil and magnets fixed). Its source in the tangent problem is
f_c = -∂R/∂δ_c, the derivative of the bias residual R on morphed meshes of the same topology
(:func:`approach_residuals`); the coil's flux linkage of K_t⁻¹ f_c is ∂Λ/∂δ_c
(:mod:`msens.magnetics.potentials`), checked by re-solving the nonlinear problem on the
morphed meshes (:func:`approach_flux_change`). Re-meshing at a different flat radius was
rejected: the mesh-to-mesh noise of the coil's bias flux linkage (~1e-4 relative) is about
1000 times the effect. Finite approaches up to an open gap, on one mesh per contact:
:mod:`msens.magnetics.contact_map`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import skfem

from msens.errors import internal, require
from msens.field.forms import quadrature_data
from msens.field.geometry import SensorGeometry
from msens.field.parts import Coil
from msens.field.sensor_model import shell_function
from msens.field.solve import FieldSolution
from msens.magnetics.potentials import bias_residual, nonlinear_resolve
from msens.magnetics.villari import dof_flux_linkage
from msens.mechanics.hertz import hertz_approach, hertz_sphere_sphere
from msens.params.materials import BEAD_STEEL, ElasticMaterial


def _morphed_quadrature(sol: FieldSolution, points: np.ndarray):
    """Quadrature data of the model's mesh on vertex coordinates ``points`` (shape (2, n)).

    Only the stretched elements are evaluated again: an element whose vertices all move by
    one axial shift is translated along the axis, which leaves its axisymmetric quadrature
    data unchanged (the bias solution's)."""
    q = sol.disc.quad
    t = sol.problem.mesh.mesh.t
    move = sol.problem.mesh.mesh.p - points
    stretched = np.flatnonzero((np.ptp(move[1][t], axis=0) > 0)
                               | np.any(move[0][t] != 0, axis=0))
    if stretched.size == 0:
        return q
    sub = _element_quadrature(sol, points, stretched)
    probe = _element_quadrature(sol, sol.problem.mesh.mesh.p, stretched[:8])
    internal(bool(np.allclose(probe.g, q.g[stretched[:8]], rtol=1e-9,
                              atol=1e-12 * np.max(np.abs(probe.g)))),
             "internal: the sub-mesh's basis functions differ from the model's")
    out = {k: getattr(q, k).copy() for k in ("g", "phi", "w", "r")}
    for k, v in out.items():
        v[stretched] = getattr(sub, k)
    return replace(q, **out)


def _element_quadrature(sol: FieldSolution, points: np.ndarray, elements: np.ndarray):
    """Quadrature data of ``elements`` on vertex coordinates ``points`` (shape (2, n)), with
    the model's global dofs: a small mesh of those elements only, so a morph that stretches
    a few elements costs a few elements."""
    t = sol.problem.mesh.mesh.t[:, elements]
    vertices, local = np.unique(t, return_inverse=True)
    # skfem keeps each triangle's vertex order (sort_t is off), so the local basis functions
    # and their dofs are those of the model's elements (checked in approach_residuals)
    sub = skfem.MeshTri(np.ascontiguousarray(points[:, vertices]),
                        np.ascontiguousarray(local.reshape(t.shape)))
    q = quadrature_data(skfem.CellBasis(sub, sol.basis.elem, intorder=2 * sol.problem.order))
    return replace(q, dofs=sol.basis.element_dofs[:, elements])


def approach_residuals(sol: FieldSolution, geometry: SensorGeometry,
                       contacts: Sequence[int], step: float = 1e-10) -> dict[int, np.ndarray]:
    """∂R/∂δ_c of the bias residual for the approach δ_c at each contact (central difference).

    The approach δ_c moves every modelled bead above contact c (particles first..c) rigidly
    toward the wall by δ_c; the coil, magnets and the beads below stay. On the fixed mesh
    topology the beads' vertices (including the shared flat of contact c) move and the
    adjacent elements stretch, so the residual is differentiated without re-meshing noise.
    Only the stretched elements (vertices both moved and fixed) are evaluated: an element
    that moves whole is translated along the axis, which leaves its part of the axisymmetric
    residual unchanged.

    Returns
    -------
    dict of int -> ndarray, shape (n_dofs,)
        Per radian, A per metre of approach.
    """
    require(step > 0, f"step must be > 0 m, got {step}")
    b = geometry.beads
    p0 = sol.problem.mesh.mesh.p
    t = sol.problem.mesh.mesh.t
    out = {}
    for c in contacts:
        require(b.first <= c <= b.last, f"contact {c} is not below a modelled bead")
        phi = shell_function(sol, [f"bead_{p}" for p in range(b.first, c + 1)], layers=0)
        stretched = np.flatnonzero(np.ptp(phi[t], axis=0) > 0)
        if not out:  # the sub-mesh keeps the model's local basis order (checked once)
            here = _element_quadrature(sol, p0, stretched)
            ref = sol.disc.quad.g[stretched]
            internal(bool(np.allclose(here.g, ref, rtol=1e-9,
                                      atol=1e-12 * np.max(np.abs(ref)))),
                     "internal: the sub-mesh's basis functions differ from the model's")
        res = []
        for s in (step, -step):
            p = p0.copy()
            p[1] -= s * phi
            res.append(bias_residual(sol, _element_quadrature(sol, p, stretched), sol.a,
                                     elements=stretched))
        out[int(c)] = (res[0] - res[1]) / (2 * step)
    return out


def hertz_stiffness(radius: float, material: ElasticMaterial = BEAD_STEEL) -> float:
    """Hertz prefactor A of two identical spheres, F = A δ^{3/2}, N/m^1.5.

    A = E√(2R)/(3(1-ν²)) (:func:`msens.mechanics.hertz.hertz_sphere_sphere`).
    """
    e, nu = material.youngs_modulus, material.poisson_ratio
    return float(hertz_sphere_sphere(e, nu, radius, e, nu, radius))


def hertz_approach_rate(force: float, radius: float,
                        material: ElasticMaterial = BEAD_STEEL) -> float:
    """dδ/dF = 2δ/(3F) of two identical spheres at ``force`` (N), m/N."""
    require(force > 0, f"force must be > 0 N, got {force}")
    return 2.0 / 3.0 * float(hertz_approach(force, hertz_stiffness(radius, material))) / force


def morphed_flux_linkage(sol: FieldSolution, geometry: SensorGeometry,
                         approaches: Mapping[int, float], coil: Coil, *, tol: float = 1e-12,
                         max_iter: int = 20) -> float:
    """Coil flux linkage after finite contact approaches, by a full nonlinear re-solve.

    The mesh is morphed as in :func:`approach_residuals`, all contacts at once: the approach
    δ_c of contact c moves every modelled bead above it rigidly toward the wall (negative:
    away from it), so bead p moves by Σ_{c ≥ p} δ_c.

    Parameters
    ----------
    approaches : mapping of int -> float
        Contact number -> δ_c, m.

    Returns
    -------
    float
        Λ, Wb.
    """
    b = geometry.beads
    p = sol.problem.mesh.mesh.p.copy()
    for contact, delta in approaches.items():
        phi = shell_function(sol, [f"bead_{q}" for q in range(b.first, contact + 1)],
                             layers=0)
        p[1] -= delta * phi
    a = nonlinear_resolve(sol, _morphed_quadrature(sol, p), tol=tol, max_iter=max_iter)
    # the coil does not move: its quadrature on the morphed mesh is the original one
    return dof_flux_linkage(sol, a, coil)


def approach_flux_change(sol: FieldSolution, geometry: SensorGeometry, contact: int,
                         coil: Coil, step: float = 1e-9, *, tol: float = 1e-12,
                         max_iter: int = 20) -> float:
    """∂Λ_bias/∂δ_c by re-solving the nonlinear problem on the morphed meshes (the check).

    Returns
    -------
    float
        Wb/m, central difference (Λ(+step) - Λ(-step)) / (2 step).
    """
    lam = [morphed_flux_linkage(sol, geometry, {contact: s}, coil, tol=tol, max_iter=max_iter)
           for s in (step, -step)]
    return (lam[0] - lam[1]) / (2 * step)


__all__ = ["approach_flux_change", "approach_residuals", "hertz_approach_rate",
           "hertz_stiffness", "morphed_flux_linkage"]
