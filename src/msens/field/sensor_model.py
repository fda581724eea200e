"""The MsS field model: bias field, bead fields, contact forces, coil R and L.

Pipeline: :class:`~msens.field.geometry.SensorGeometry` -> cached gmsh mesh -> regions (beads
and pole pieces nonlinear steel on the geometry's B–H curve, default 1018; magnets on their
recoil line, windings, air) -> nonlinear bias solve (:func:`msens.field.solve.solve`) ->
post-processing:

- B at each bead centre (on the axis, B_z = 2 dA/dr there);
- the static compression each contact carries from the magnetic forces: minus the axial force
  on the group of beads above the contact. The force is the eggshell form of the Maxwell stress,
  F_z = -∫_air (T·∇φ)_z dV with φ the P1 function equal to 1 on the group's vertices and 0 on
  all others, plus, where the group touches the bead below through the contact flat, the
  vacuum stress of an infinitesimal gap on the flat, -∫_flat (B_z² - (μ0 H_r)²)/(2μ0) dA
  (B_z and H_r are continuous across such a gap);
- coil resistance from the wire, air-core and incremental inductance (1 A per coil).

The magnet is an equivalent ring magnet (see :class:`~msens.field.parts.BiasMagnet`), not the
paper's undocumented bridge magnet.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import skfem

from msens.field.bh import monotone_bh
from msens.field.bias_cache import solve_bias
from msens.field.build import MeshOptions
from msens.field.cache import cached_mesh
from msens.field.constitutive import energy_density, reluctivities
from msens.field.forms import flux_density_qp, potential_qp
from msens.field.geometry import SensorGeometry
from msens.field.mesh import AxiMesh, from_arrays, read_gmsh
from msens.field.parts import Coil
from msens.field.regions import Air, CurrentRegion, NonlinearSoft, PermanentMagnet, Region
from msens.field.solve import FieldSolution, MagnetostaticProblem, incremental, solve
from msens.params.materials import BHCurve
from msens.params.units import MU0, RHO_COPPER, TWO_PI
from msens.store import Store

_log = logging.getLogger(__name__)

#: Statement carried into every output that uses the magnet.
MAGNET_NOTE = ("bias magnet is an axisymmetric EQUIVALENT (axial ring magnet + two 1018-steel "
               "pole pieces), not the paper's undocumented bridge magnet McMaster-Carr 5841K12")


# ----------------------------------------------------------------------------- regions

def regions_for(geometry: SensorGeometry, names: Sequence[str], *, magnets: bool = True,
                steel: bool = True) -> dict[str, Region]:
    """What fills each mesh subdomain.

    Parameters
    ----------
    geometry : SensorGeometry
    names : sequence of str
        Subdomain names of the mesh.
    magnets : bool
        False switches the remanence off and makes magnets air (air-core runs).
    steel : bool
        False makes beads and pole pieces air (air-core runs); True gives them the
        nonlinear curve ``geometry.steel``.
    """
    magnet = {f"magnet_{u.magnet.particle}": u.magnet for u in geometry.sensors
              if u.magnet is not None}
    soft = NonlinearSoft(geometry.steel, reversibility=geometry.reversibility)
    out: dict[str, Region] = {}
    for name in names:
        if name.startswith(("bead_", "pole_")):
            out[name] = soft if steel else Air()
        elif name in magnet:
            m = magnet[name]
            out[name] = (PermanentMagnet(m.remanence, m.recoil_permeability) if magnets
                         else Air())
        elif name.startswith("coil_"):
            out[name] = CurrentRegion(0.0)
        else:
            out[name] = Air()
    return out


def coil_current_density(coil: Coil, current: float = 1.0) -> float:
    """Homogenised J_φ = N I / S of a winding, A/m²."""
    return coil.turns * current / coil.area


def coil_resistance(coil: Coil, resistivity: float = RHO_COPPER) -> float:
    """DC resistance of the winding, Ohm: ρ N ℓ_mean / (π d_bare²/4) (copper at 20 °C)."""
    return resistivity * coil.turns * coil.mean_turn_length / (
        math.pi * coil.wire.bare_diameter**2 / 4)


# ----------------------------------------------------------------------------- evaluation

def flux_density_at(sol: FieldSolution, r: np.ndarray, z: np.ndarray) -> np.ndarray:
    """B = (B_r, B_z) at points, T, shape (n, 2); on the axis B_z = 2 ∂A/∂r.

    Parameters
    ----------
    sol : FieldSolution
    r, z : array_like, broadcastable to shape (n,)
        Points in the meridian plane, m (inside the mesh; skfem's element finder raises
        otherwise).
    """
    basis = sol.basis
    mesh, elem = basis.mesh, basis.elem
    r, z = (np.atleast_1d(v).ravel() for v in np.broadcast_arrays(
        np.asarray(r, dtype=float), np.asarray(z, dtype=float)))
    cells = mesh.element_finder()(r, z)
    out = np.zeros((r.size, 2))
    for k, e in enumerate(cells):
        tind = np.array([e])
        xref = basis.mapping.invF(np.array([[[r[k]]], [[z[k]]]]), tind=tind)[:, 0, :]
        a_val, da = 0.0, np.zeros(2)
        for i, dof in enumerate(basis.element_dofs[:, e]):
            f = elem.gbasis(basis.mapping, xref, i, tind=tind)[0]
            a_val += sol.a[dof] * np.asarray(f)[0, 0]
            da += sol.a[dof] * f.grad[:, 0, 0]
        out[k] = (-da[1], da[0] + (a_val / r[k] if r[k] > 0 else da[0]))
    return out


def _p1_gradients(mesh: skfem.MeshTri, phi: np.ndarray) -> np.ndarray:
    """Constant gradient of a P1 vertex function on every triangle, shape (n_elements, 2)."""
    p, t = mesh.p, mesh.t
    x0, x1, x2 = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    det = (x1[0] - x0[0]) * (x2[1] - x0[1]) - (x2[0] - x0[0]) * (x1[1] - x0[1])
    f0, f1, f2 = phi[t[0]], phi[t[1]], phi[t[2]]
    gx = ((f1 - f0) * (x2[1] - x0[1]) - (f2 - f0) * (x1[1] - x0[1])) / det
    gy = ((f2 - f0) * (x1[0] - x0[0]) - (f1 - f0) * (x2[0] - x0[0])) / det
    return np.stack([gx, gy], axis=-1)


def shell_function(sol: FieldSolution, bodies: Sequence[str], layers: int = 0) -> np.ndarray:
    """P1 vertex function φ of the eggshell: 1 on the bodies, 0 on all other non-air parts.

    With ``layers`` = L > 0, air vertices L' <= L edges (through air triangles) away from the
    bodies get φ = 1 - L'/(L + 1), so φ falls to 0 over L + 1 element layers; vertices of any
    other non-air region stay 0. Shape (n_vertices,).
    """
    axi = sol.problem.mesh
    mesh = axi.mesh
    body_el = np.concatenate([axi.subdomains[n] for n in bodies])
    phi = np.zeros(mesh.p.shape[1])
    phi[np.unique(mesh.t[:, body_el])] = 1.0
    solid = np.zeros(mesh.p.shape[1], dtype=bool)
    air_el = []
    for n, reg in sol.problem.regions.items():
        if isinstance(reg, Air):
            air_el.append(axi.subdomains[n])
        elif n not in bodies:
            solid[mesh.t[:, axi.subdomains[n]].ravel()] = True
    t_air = mesh.t[:, np.concatenate(air_el)]
    reached = phi > 0
    for k in range(1, layers + 1):
        touch = np.any(reached[t_air], axis=0)
        new = np.zeros_like(reached)
        new[t_air[:, touch].ravel()] = True
        new &= ~reached & ~solid
        phi[new] = 1.0 - k / (layers + 1)
        reached |= new
    return phi


def group_force(sol: FieldSolution, bodies: Sequence[str],
                flats: Sequence[str] = (), layers: int = 0) -> float:
    """Axial magnetic force on the union of ``bodies``, N (eggshell Maxwell stress).

    Parameters
    ----------
    sol : FieldSolution
        A bias solution.
    bodies : sequence of str
        Subdomain names of the group (e.g. all beads above a contact).
    flats : sequence of str
        Boundary groups where the group touches other steel (contact flats on the group's
        *lower* side); each adds the vacuum stress of an infinitesimal gap.
    layers : int
        Extra element layers over which φ falls to 0 (see :func:`shell_function`); the result
        must not depend on it beyond discretisation error.

    Returns
    -------
    float
        F_z, N (negative = pulled down).
    """
    axi = sol.problem.mesh
    grad_phi = _p1_gradients(axi.mesh, shell_function(sol, bodies, layers))
    air = np.concatenate([axi.subdomains[n] for n, reg in sol.problem.regions.items()
                          if isinstance(reg, Air)])
    air = air[np.any(grad_phi[air] != 0.0, axis=1)]
    q = sol.disc.quad
    b = flux_density_qp(q, sol.a)[air]  # (k, nq, 2)
    br, bz = b[..., 0], b[..., 1]
    gr, gz = grad_phi[air, 0][:, None], grad_phi[air, 1][:, None]
    t_dot = (bz * br * gr + 0.5 * (bz**2 - br**2) * gz) / MU0
    force = -TWO_PI * float(np.sum(q.w[air] * t_dot))
    for name in flats:
        force += _flat_force(sol, name)
    return force


def _flat_curve(sol: FieldSolution, boundary: str) -> BHCurve:
    """B–H curve of the bead above the contact flat ``contact_<k>_<k+1>`` (bead ``k``)."""
    upper = f"bead_{boundary.split('_')[1]}"
    region = sol.problem.regions.get(upper)
    if not isinstance(region, NonlinearSoft):
        raise ValueError(f"contact flat {boundary!r}: the bead above it, {upper!r}, is not a "
                         "nonlinear steel region")
    return region.curve


def _flat_force(sol: FieldSolution, boundary: str) -> float:
    """-∫ (B_z² - (μ0 H_r)²)/(2 μ0) dA over a contact flat (force on the body above it).

    H_r is evaluated with the upper bead's B–H curve (H_r is continuous across the flat).
    """
    axi = sol.problem.mesh
    facets = axi.boundaries[boundary]
    fb = skfem.FacetBasis(axi.mesh, sol.basis.elem, facets=facets,
                          intorder=2 * sol.problem.order + 2)
    a = fb.interpolate(sol.a)
    r = np.asarray(fb.global_coordinates())[0]
    da = a.grad
    br = -da[1]
    bz = da[0] + np.asarray(a) / r
    law = monotone_bh(_flat_curve(sol, boundary))
    bmag = np.sqrt(br**2 + bz**2)
    mu0_hr = MU0 * law.reluctivity(bmag) * br
    integrand = (bz**2 - mu0_hr**2) / (2 * MU0) * TWO_PI * r
    return -float(np.sum(integrand * fb.dx))


def total_energy(sol: FieldSolution) -> float:
    """Stored energy Π = ∫ w(B) dV (magnets on their recoil line), J."""
    q = sol.disc.quad
    b = flux_density_qp(q, sol.a)
    nu, _ = reluctivities(sol.disc.materials, b)
    return TWO_PI * float(np.sum(energy_density(sol.disc.materials, b, nu) * q.w))


def virtual_work_force(sol: FieldSolution, bodies: Sequence[str], delta: float = 1e-8,
                       layers: int = 2, **solve_kw) -> float:
    """Axial force on ``bodies`` by virtual work: F = -dΠ/dx at fixed remanence, N.

    The group's vertices are moved rigidly by ±``delta`` along z and the air around them is
    stretched by the shell function φ of :func:`shell_function` (``layers`` thick, so only air
    elements deform); Π is recomputed on both morphed meshes (two nonlinear solves) and
    differenced. Valid only when the bodies touch nothing but air (``contact_gap > 0``).
    """
    axi = sol.problem.mesh
    mesh = axi.mesh
    phi = shell_function(sol, bodies, layers)
    others = np.concatenate([axi.subdomains[n] for n, reg in sol.problem.regions.items()
                             if not isinstance(reg, Air) and n not in bodies])
    if np.any(phi[mesh.t[:, others]] != 0):
        raise ValueError("virtual_work_force: the bodies touch other non-air regions")
    energies = []
    for s in (+delta, -delta):
        p = mesh.p.copy()
        p[1] += s * phi
        moved = from_arrays(p, mesh.t, axi.subdomains, axi.boundaries)
        prob = replace(sol.problem, mesh=moved)
        energies.append(total_energy(solve(prob, initial=sol.a, **solve_kw)))
    return -(energies[0] - energies[1]) / (2 * delta)


def coil_flux_linkage(sol: FieldSolution, coil_region: str, coil: Coil) -> float:
    """Λ = (N/S) ∫_coil 2π r A dS, Wb."""
    el = sol.problem.mesh.subdomains[coil_region]
    q = sol.disc.quad
    a = potential_qp(q, sol.a)[el]
    return coil.turns / coil.area * TWO_PI * float(np.sum(a * q.w[el]))


# ----------------------------------------------------------------------------- results

@dataclass(frozen=True)
class CoilResult:
    """Electrical data of one coil.

    Attributes
    ----------
    particle : int
    turns : int
    resistance_ohm : float
        DC resistance at 20 °C, Ohm.
    inductance_H : float
        Incremental inductance at the bias point (1 A), H.
    air_core_inductance_H : float
        Inductance with no steel and no magnets, H.
    inner_radius_m, outer_radius_m, length_m : float
        Winding dimensions, m.
    """

    particle: int
    turns: int
    resistance_ohm: float
    inductance_H: float
    air_core_inductance_H: float
    inner_radius_m: float
    outer_radius_m: float
    length_m: float


@dataclass(frozen=True)
class BeadField:
    """Bias flux density of a bead.

    Attributes
    ----------
    particle : int
    B_center_T : tuple of float
        (B_r, B_z) at the bead centre, T.
    Bz_mean_T : float
        Volume average of B_z over the bead, T (the 3-D average of the vector B is
        (0, 0, Bz_mean): e_r averages out around the axis).
    """

    particle: int
    B_center_T: tuple[float, float]
    Bz_mean_T: float


@dataclass(frozen=True)
class ContactForce:
    """Static compression a contact carries from magnetic forces, N (positive = compressed).

    It is minus the axial magnetic force on all modelled beads above the contact."""

    upper: int
    lower: int
    magnetic_force_N: float


@dataclass(frozen=True)
class FieldReport:
    """Everything :func:`run_field_model` computes.

    Attributes
    ----------
    geometry : SensorGeometry
    coils : tuple of CoilResult
    beads : tuple of BeadField
    contacts : tuple of ContactForce
    axis_z_m, axis_Bz_T : ndarray, shape (n,)
        Axial bias profile B_z(0, z), m and T.
    newton_iterations : int
    newton_residuals : tuple of float
    dofs : int
    elements : int
    mesh_path : Path
    solution : FieldSolution
        The bias solution (for VTU export and figures; not serialised).
    note : str
        The magnet-equivalence statement.
    """

    geometry: SensorGeometry
    coils: tuple[CoilResult, ...]
    beads: tuple[BeadField, ...]
    contacts: tuple[ContactForce, ...]
    axis_z_m: np.ndarray
    axis_Bz_T: np.ndarray
    newton_iterations: int
    newton_residuals: tuple[float, ...]
    dofs: int
    elements: int
    mesh_path: Path
    solution: FieldSolution = field(repr=False, compare=False)
    note: str = MAGNET_NOTE


def load_mesh(geometry: SensorGeometry, options: MeshOptions | None = None,
              store: Store | None = None) -> tuple[AxiMesh, Path]:
    """Mesh of ``geometry`` from ``store`` (built when missing; default
    :meth:`msens.store.Store.default`), read as :class:`AxiMesh`."""
    path = cached_mesh(geometry, options, store)
    return read_gmsh(path), path


def bias_problem(geometry: SensorGeometry, axi: AxiMesh) -> MagnetostaticProblem:
    """The nonlinear bias problem (magnets on, coils unexcited), A = 0 on the box."""
    return MagnetostaticProblem(axi, regions_for(geometry, list(axi.subdomains)))


def bead_fields(sol: FieldSolution, geometry: SensorGeometry) -> tuple[BeadField, ...]:
    """B at every modelled bead centre."""
    parts = list(geometry.beads.particles)
    z = np.array([geometry.beads.center(p) for p in parts])
    b = flux_density_at(sol, np.zeros_like(z), z)
    q = sol.disc.quad
    bq = flux_density_qp(q, sol.a)
    out = []
    for p, v in zip(parts, b, strict=True):
        el = sol.problem.mesh.subdomains[f"bead_{p}"]
        w = q.w[el]
        mean = float(np.sum(w * bq[el, :, 1]) / w.sum())
        out.append(BeadField(p, (float(v[0]), float(v[1])), mean))
    return tuple(out)


def magnetic_contact_forces(sol: FieldSolution, geometry: SensorGeometry,
                   contacts: Sequence[tuple[int, int]] | None = None
                   ) -> tuple[ContactForce, ...]:
    """Magnetic static compression at each (upper, lower) contact (default: all modelled)."""
    b = geometry.beads
    out = []
    for upper, lower in contacts or b.contacts:
        group = [f"bead_{p}" for p in range(b.first, upper + 1)]
        flat = f"contact_{upper}_{lower}"
        flats = [flat] if flat in sol.problem.mesh.boundaries else []
        out.append(ContactForce(upper, lower, -group_force(sol, group, flats)))
    return tuple(out)


def coil_results(sol: FieldSolution, geometry: SensorGeometry) -> tuple[CoilResult, ...]:
    """R, incremental L (at the bias point) and air-core L of every coil (1 A each)."""
    axi = sol.problem.mesh
    air_regions = regions_for(geometry, list(axi.subdomains), magnets=False, steel=False)
    out = []
    for unit in geometry.iter_units():
        c = unit.coil
        name = f"coil_{c.particle}"
        j = coil_current_density(c)
        inc = incremental(sol, {name: CurrentRegion(j)})
        air = dict(air_regions)
        air[name] = CurrentRegion(j)
        air_sol = solve(MagnetostaticProblem(axi, air))
        out.append(CoilResult(
            particle=c.particle, turns=c.turns, resistance_ohm=coil_resistance(c),
            inductance_H=coil_flux_linkage(inc, name, c),
            air_core_inductance_H=coil_flux_linkage(air_sol, name, c),
            inner_radius_m=c.inner_radius, outer_radius_m=c.outer_radius, length_m=c.length))
    return tuple(out)


def axis_profile(sol: FieldSolution, geometry: SensorGeometry, n: int = 401
                 ) -> tuple[np.ndarray, np.ndarray]:
    """B_z on the axis over the box (excluding the last 1 % at each end), m and T."""
    box = geometry.box()
    pad = 0.01 * (box.z1 - box.z0)
    z = np.linspace(box.z0 + pad, box.z1 - pad, n)
    return z, flux_density_at(sol, np.zeros_like(z), z)[:, 1]


def run_field_model(geometry: SensorGeometry, *,
                    options: MeshOptions | None = None, store: Store | None = None,
                    inductance: bool = True) -> FieldReport:
    """Mesh (cached), solve the bias field (cached, :func:`msens.field.bias_cache.solve_bias`)
    and post-process the sensor model.

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    store : Store, optional
        Where the mesh and the bias solution are found or written (default
        :meth:`msens.store.Store.default`).
    inductance : bool
        False skips the two extra linear solves per coil.

    Returns
    -------
    FieldReport
    """
    from msens.progress import heartbeat, stopwatch

    _log.info("field model: mesh (cached on disk) and nonlinear bias solve")
    elapsed = stopwatch()
    with heartbeat(_log, "field model: mesh and bias solve"):
        axi, path = load_mesh(geometry, options, store)
        sol = solve_bias(bias_problem(geometry, axi), geometry, options, store)
    _log.info("field model: %d dofs, %d Newton iterations, %.1f s", sol.dofs, sol.iterations,
              elapsed())
    with heartbeat(_log, "field model: coil inductances, bead fields, contact forces"):
        coils = coil_results(sol, geometry) if inductance else tuple(
            CoilResult(u.coil.particle, u.coil.turns, coil_resistance(u.coil), math.nan,
                       math.nan, u.coil.inner_radius, u.coil.outer_radius, u.coil.length)
            for u in geometry.iter_units())
        return field_report(geometry, sol, path, coils)


def field_report(geometry: SensorGeometry, sol: FieldSolution, mesh_path: Path,
                 coils: tuple[CoilResult, ...]) -> FieldReport:
    """The report of a solved bias field: the coils' results (:func:`coil_results`) with
    the bead fields, the magnetic contact forces and the axis profile.

    The last stage of :func:`run_field_model`, separate so that a workflow can run (and
    time) the stages itself: :func:`load_mesh`, :func:`msens.field.solve.solve` of
    :func:`bias_problem`, :func:`coil_results`, this.
    """
    beads = bead_fields(sol, geometry)
    contacts = magnetic_contact_forces(sol, geometry)
    z, bz = axis_profile(sol, geometry)
    return FieldReport(
        geometry=geometry, coils=coils, beads=beads, contacts=contacts, axis_z_m=z,
        axis_Bz_T=bz, newton_iterations=sol.iterations, newton_residuals=sol.residuals,
        dofs=sol.dofs, elements=sol.problem.mesh.n_elements, mesh_path=mesh_path,
        solution=sol)


__all__ = [
    "MAGNET_NOTE",
    "BeadField",
    "CoilResult",
    "ContactForce",
    "FieldReport",
    "axis_profile",
    "bead_fields",
    "bias_problem",
    "coil_current_density",
    "coil_flux_linkage",
    "coil_resistance",
    "coil_results",
    "field_report",
    "flux_density_at",
    "group_force",
    "load_mesh",
    "magnetic_contact_forces",
    "regions_for",
    "run_field_model",
    "shell_function",
    "total_energy",
    "virtual_work_force",
]
