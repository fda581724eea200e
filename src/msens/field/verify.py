"""Verification of the field solver against exact solutions (``msens verify``).

Each ``check_*`` function builds a small gmsh mesh, solves, and compares with a closed form
(:mod:`.analytic`), returning :class:`Row` records; :func:`run_all` runs them all
and :func:`format_table` prints them. The meshes are coarse on purpose (the default suite runs
in seconds) yet inside the stated tolerances; :func:`check_convergence` shows the order.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from msens.field import analytic
from msens.field.bh import monotone_bh
from msens.field.mesh import AxiMesh, refined
from msens.field.post import energy, field_strength, flux_density, flux_linkage, force_z
from msens.field.regions import Air, CurrentRegion, LinearMagnetic, NonlinearSoft, PermanentMagnet
from msens.field.solve import MagnetostaticProblem, solve
from msens.field.verification_geometry import (
    Part,
    build_mesh,
    rect_mesh,
    sphere_mesh,
    two_spheres_mesh,
)
from msens.params.materials import STEEL_1018_BH, BHCurve
from msens.params.units import MU0
from msens.readout.coil import coil_from


@dataclass(frozen=True)
class Row:
    """One verification result.

    Attributes
    ----------
    name : str
    computed, reference : float
        In ``unit``.
    unit : str
    rel_error : float
        |computed − reference| / |reference| unless the name says otherwise
        (field profiles: max deviation over the points / max |reference|).
    tolerance : float
        Largest accepted ``rel_error``.
    passed : bool
    """

    name: str
    computed: float
    reference: float
    unit: str
    rel_error: float
    tolerance: float
    passed: bool


def _row(name: str, computed: float, reference: float, unit: str, tol: float,
         rel_error: float | None = None) -> Row:
    err = abs(computed - reference) / abs(reference) if rel_error is None else rel_error
    return Row(name, float(computed), float(reference), unit, float(err), tol, bool(err <= tol))


def _profile_row(name: str, computed: np.ndarray, reference: np.ndarray, tol: float) -> Row:
    """Max deviation over a profile, normalised by the largest |reference|."""
    scale = float(np.max(np.abs(reference)))
    err = float(np.max(np.abs(computed - reference)) / scale)
    i = int(np.argmax(np.abs(reference)))
    return _row(name, computed[i], reference[i], "T", tol, rel_error=err)


def check_sphere(mu_r: float = 100.0, radius: float = 0.01, b0: float = 0.01) -> list[Row]:
    """Linear sphere in a uniform field B0 (imposed as A = B0 r/2 on the outer boundary).

    Exact: H inside is uniform, 3 H0/(μ_r + 2). The outer boundary at 15 radii perturbs it by
    ~ 2 (a/R)³ = 6e-4 relative.
    """
    mesh = sphere_mesh(radius, 15 * radius, radius / 12, h_far=2 * radius)
    sol = solve(MagnetostaticProblem(mesh, {"sphere": LinearMagnetic(mu_r), "air": Air()},
                                     background_field=b0))
    rs = np.array([0.0, 0.3, 0.5, 0.2, 0.6]) * radius
    zs = np.array([0.0, 0.0, 0.4, -0.6, -0.3]) * radius
    h = field_strength(sol, rs, zs)
    ref = analytic.sphere_interior_h(b0 / MU0, mu_r)
    err = float(np.max(np.hypot(h[:, 0], h[:, 1] - ref)) / ref)
    return [_row(f"sphere mu_r={mu_r:g}: H inside (5 points)", h[0, 1], ref, "A/m", 5e-3,
                 rel_error=err)]


def nonlinear_sphere_exact(b0: float, curve: BHCurve = STEEL_1018_BH) -> tuple[float, float]:
    """Exact uniform (B, H) inside a nonlinear sphere in a uniform field B0, (T, A/m).

    A uniformly magnetised sphere has demagnetising factor 1/3 whatever M(H) is, so the
    interior field stays uniform and solves B + 2 μ0 H(B) = 3 B0 (H0 − H = M/3, B = μ0 (H + M)).
    """
    law = monotone_bh(curve)
    b = brentq(lambda x: x + 2 * MU0 * float(law.field_strength(np.array(x))) - 3 * b0,
               0.0, 3 * b0)
    return b, float(law.field_strength(np.array(b)))


def check_nonlinear_sphere(b0: float = 0.7, radius: float = 0.01) -> list[Row]:
    """1018-steel sphere in B0 = 0.7 T (knee of the curve): Newton vs the exact scalar law."""
    mesh = sphere_mesh(radius, 15 * radius, radius / 12, h_far=2 * radius)
    sol = solve(MagnetostaticProblem(mesh, {"sphere": NonlinearSoft(STEEL_1018_BH),
                                            "air": Air()}, background_field=b0))
    b_ref, h_ref = nonlinear_sphere_exact(b0)
    rs, zs = np.array([0.0, 0.4, 0.2]) * radius, np.array([0.0, 0.3, -0.5]) * radius
    b = flux_density(sol, rs, zs)
    h = field_strength(sol, rs, zs)
    err_b = float(np.max(np.hypot(b[:, 0], b[:, 1] - b_ref)) / b_ref)
    err_h = float(np.max(np.hypot(h[:, 0], h[:, 1] - h_ref)) / h_ref)
    return [_row(f"1018 sphere in {b0:g} T: B inside (3 points)", b[0, 1], b_ref, "T", 5e-3,
                 rel_error=err_b),
            _row(f"1018 sphere in {b0:g} T: H inside (3 points)", h[0, 1], h_ref, "A/m", 2e-2,
                 rel_error=err_h),
            _row(f"1018 sphere: Newton iterations ({sol.iterations}) <= 15",
                 sol.iterations, 15, "-", 0.0, rel_error=0.0 if sol.iterations <= 15 else 1.0)]


def check_truncation(r_out: float = 0.4) -> list[Row]:
    """Open-boundary truncation: A = 0 at ``r_out`` vs the exact far potential, same mesh.

    Thick solenoid of size 40 mm; the difference is the truncation error alone.
    """
    r1, r2, length, j = 0.01, 0.02, 0.02, 1e6
    mesh = rect_mesh("coil", r1, r2, length, r_out, 1.0e-3, r_out / 10)
    regions = {"coil": CurrentRegion(j), "air": Air()}
    z = np.linspace(-1.5, 1.5, 7) * length
    b_cut = flux_density(solve(MagnetostaticProblem(mesh, regions)), 0.0, z)[:, 1]
    exact_bc = MagnetostaticProblem(mesh, regions,
                                    outer_potential=_solenoid_potential(r1, r2, length, j))
    b_open = flux_density(solve(exact_bc), 0.0, z)[:, 1]
    return [_profile_row(f"truncation at R = {r_out:g} m (10x coil size): on-axis Bz",
                         b_cut, b_open, 1e-3)]


def check_thin_solenoid(radius: float = 0.01, thickness: float = 0.2e-3, length: float = 0.04,
                        j: float = 1e7) -> list[Row]:
    """Thin winding vs the current-sheet formula (n I = J t, sheet at the mean radius).

    The finite thickness t changes the field by O((t/R)²) = 4e-4 of the centre value at most.
    """
    mesh = build_mesh([Part("coil", "rect", (radius - thickness / 2, radius + thickness / 2,
                                             -length / 2, length / 2), thickness / 2)],
                      r_out=0.5, h_far=0.05, grading=0.25,
                      sizing=[Part("axis", "rect", (0.0, radius, -length, length), 1.5e-3)])
    sol = solve(MagnetostaticProblem(mesh, {"coil": CurrentRegion(j), "air": Air()}))
    z = np.linspace(-0.75, 0.75, 7) * length
    fe = flux_density(sol, 0.0, z)[:, 1]
    ref = analytic.thin_solenoid_bz(z, radius, length, j * thickness, 1.0)
    return [_profile_row("thin solenoid: on-axis Bz (7 points)", fe, ref, 3e-3)]


def check_thick_solenoid(r1: float = 0.01, r2: float = 0.02, length: float = 0.02,
                         j: float = 1e6) -> list[Row]:
    """Thick winding (uniform J) vs the exact on-axis integral."""
    mesh = rect_mesh("coil", r1, r2, length, 0.4, 1.0e-3, 0.04)
    sol = solve(MagnetostaticProblem(mesh, {"coil": CurrentRegion(j), "air": Air()}))
    z = np.linspace(-1.5, 1.5, 7) * length
    fe = flux_density(sol, 0.0, z)[:, 1]
    ref = analytic.thick_solenoid_bz(z, r1, r2, length, j)
    return [_profile_row("thick solenoid: on-axis Bz (7 points)", fe, ref, 3e-3)]


def check_ring_magnet(r_in: float = 0.005, r_out: float = 0.015, length: float = 0.01,
                      remanence: float = 1.0) -> list[Row]:
    """Axially magnetised ring (μ_rec = 1) vs the exact on-axis field (two cylinders)."""
    mesh = rect_mesh("magnet", r_in, r_out, length, 0.3, 0.6e-3, 0.03)
    sol = solve(MagnetostaticProblem(mesh, {"magnet": PermanentMagnet(remanence, 1.0),
                                            "air": Air()}))
    z = np.linspace(-2.0, 2.0, 9) * length
    fe = flux_density(sol, 0.0, z)[:, 1]
    ref = analytic.ring_magnet_bz(z, r_in, r_out, length, remanence)
    return [_profile_row("ring magnet: on-axis Bz (9 points)", fe, ref, 5e-3)]


#: The paper's coil (§2): 1100 turns of AWG36 on a former of inner radius 7.95 mm, 7 mm long.
PAPER_COIL = {"turns": 1100, "inner_radius": 7.95e-3, "length": 7e-3}


def paper_coil_outer_radius() -> float:
    """Winding outer radius of the paper's coil with layer (square) packing, m (11.58 mm)."""
    return coil_from(PAPER_COIL["turns"], PAPER_COIL["length"], PAPER_COIL["inner_radius"],
                     "AWG36", "square").outer_radius


def reference_inductance(r1: float, r2: float, length: float, turns: int) -> float:
    """Filament-sum inductance, Richardson-extrapolated from 24² and 48² cells (O(h²)), H."""
    coarse = analytic.coil_inductance_filaments(r1, r2, length, turns, 24, 24)
    fine = analytic.coil_inductance_filaments(r1, r2, length, turns, 48, 48)
    return fine + (fine - coarse) / 3.0


def check_inductance() -> list[Row]:
    """Air-core inductance of the paper's coil: FE (flux linkage and energy) vs filament sum."""
    r1, length, n = PAPER_COIL["inner_radius"], PAPER_COIL["length"], PAPER_COIL["turns"]
    r2 = paper_coil_outer_radius()
    mesh = rect_mesh("coil", r1, r2, length, 0.15, 0.4e-3, 0.015)
    j = n * 1.0 / ((r2 - r1) * length)
    sol = solve(MagnetostaticProblem(mesh, {"coil": CurrentRegion(j), "air": Air()}))
    l_flux = flux_linkage(sol, "coil", n)
    l_energy = 2.0 * energy(sol)
    ref = reference_inductance(r1, r2, length, n)
    return [_row("paper coil L (flux linkage) vs filament sum", l_flux, ref, "H", 1e-2),
            _row("paper coil L: 2W/I^2 vs flux linkage", l_energy, l_flux, "H", 1e-9)]


def check_two_spheres(radius: float = 0.005, distance: float = 0.015,
                      remanence: float = 1.0) -> list[Row]:
    """Two uniformly magnetised spheres (μ_rec = 1): exact dipole force, both force methods."""
    mesh = two_spheres_mesh(radius, distance, 0.15, radius / 10, h_far=0.015)
    mag = PermanentMagnet(remanence, 1.0)
    sol = solve(MagnetostaticProblem(mesh, {"lower": mag, "upper": mag, "air": Air()}))
    m = remanence / MU0 * 4.0 / 3.0 * np.pi * radius**3
    exact = -analytic.dipole_force(m, m, distance)  # force on the upper sphere, towards -z
    f_mx = force_z(sol, ["upper"], method="maxwell")
    f_vw = force_z(sol, ["upper"], method="virtual_work")
    return [_row("two magnetised spheres: Fz (eggshell Maxwell)", f_mx, exact, "N", 2e-2),
            _row("two magnetised spheres: Fz (virtual work)", f_vw, exact, "N", 2e-2),
            _row("two spheres: virtual work vs Maxwell", f_vw, f_mx, "N", 2e-2)]


def convergence_study(levels: int = 3, base_h: float = 4e-3
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Error of the thick solenoid's on-axis B_z under uniform refinement.

    The exact A_φ is imposed on the outer boundary (:func:`analytic.thick_solenoid_potential`)
    so only the discretisation error remains.

    Returns
    -------
    h : ndarray, shape (levels,)
        Nominal element size at the winding, m.
    err : ndarray, shape (levels,)
        Max |B_z − exact| over 9 axis points / B_z(0).
    order : ndarray, shape (levels − 1,)
        log2(err_k / err_{k+1}).
    """
    r1, r2, length, j = 0.01, 0.02, 0.02, 1e6
    mesh: AxiMesh = rect_mesh("coil", r1, r2, length, 0.08, base_h, 0.02)
    exact_a = _solenoid_potential(r1, r2, length, j)
    z = np.linspace(-1.5, 1.5, 9) * length
    ref = analytic.thick_solenoid_bz(z, r1, r2, length, j)
    errs = []
    for _ in range(levels):
        prob = MagnetostaticProblem(mesh, {"coil": CurrentRegion(j), "air": Air()},
                                    outer_potential=exact_a)
        fe = flux_density(solve(prob), 0.0, z)[:, 1]
        errs.append(np.max(np.abs(fe - ref)) / ref[4])
        mesh = refined(mesh)
    errs = np.array(errs)
    h = base_h / 2.0 ** np.arange(levels)
    return h, errs, np.log2(errs[:-1] / errs[1:])


def _solenoid_potential(r1: float, r2: float, length: float, j: float
                        ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    def f(r: np.ndarray, z: np.ndarray) -> np.ndarray:
        return analytic.thick_solenoid_potential(r, z, r1, r2, length, j)
    return f


def check_convergence(levels: int = 3) -> list[Row]:
    """Observed order of the on-axis B_z error for P2 (expected 2; one-sided check >= 1.8)."""
    _, _, order = convergence_study(levels)
    p = float(order[-1])
    return [_row("P2 convergence order, solenoid on-axis Bz", p, 2.0, "-", 0.1,
                 rel_error=max(0.0, (2.0 - p) / 2.0))]


CHECKS: tuple[Callable[[], list[Row]], ...] = (
    check_sphere, check_nonlinear_sphere, check_thin_solenoid, check_thick_solenoid,
    check_truncation, check_ring_magnet, check_inductance, check_two_spheres,
    check_convergence)


def run_all(progress: Callable[[Row], None] | None = None) -> list[Row]:
    """Run every field verification check; returns their rows in order.

    ``progress`` is called with each row as soon as its check has run (``msens verify``
    prints a line per check as it goes); a check that runs longer than a few seconds has a
    heartbeat (:func:`msens.progress.heartbeat`).
    """
    from msens.progress import heartbeat

    log = logging.getLogger(__name__)
    rows: list[Row] = []
    for check in CHECKS:
        with heartbeat(log, f"verify: {check.__name__.removeprefix('check_')}"):
            new = check()
        for row in new:
            if progress is not None:
                progress(row)
        rows.extend(new)
    return rows


def format_table(rows: list[Row]) -> str:
    """Plain-text table of verification rows (one line each, PASS/FAIL last)."""
    head = ("check", "computed", "reference", "unit", "rel.err", "tol", "")
    body = [(r.name, f"{r.computed:.6g}", f"{r.reference:.6g}", r.unit, f"{r.rel_error:.2e}",
             f"{r.tolerance:.1e}", "PASS" if r.passed else "FAIL") for r in rows]
    widths = [max(len(x[i]) for x in (head, *body)) for i in range(len(head))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)).rstrip()
             for line in (head, *body)]
    lines.insert(1, "-" * len(lines[0]))
    return "\n".join(lines)
