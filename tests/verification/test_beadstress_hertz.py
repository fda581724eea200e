"""Bead stress under two opposite Hertz contacts: mean-stress theorem, Hertz p0, convergence.

References: K. L. Johnson, *Contact Mechanics* (1985), §3.4 eq. (3.45) and §4.2 (Hertz);
the mean-stress theorem <sigma_ij> = (1/V) * (surface integral of x_i t_j), e.g. Landau &
Lifshitz, *Theory of Elasticity*, §2, problem 1.
"""

from __future__ import annotations

import numpy as np
import pytest

from msens.mechanics.beadmesh import BeadMeshSpec
from msens.mechanics.beadstress import hertz_axis_stress, solve_bead_stress
from msens.mechanics.stress_sampling import mean_stress, mean_stress_exact, stress_at
from msens.params.materials import BEAD_STEEL

R = 2.38e-3  # 4.76 mm beads
E, NU = BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio


@pytest.fixture(scope="module", params=[1.0, 100.0], ids=["F=1N", "F=100N"])
def bead(request):
    return solve_bead_stress(R, E, NU, request.param)


def test_mean_stress_theorem(bead):
    ms = mean_stress(bead)
    point = mean_stress_exact(R, bead.force)  # -3F / (2 pi R^2)
    assert ms["zz"] == pytest.approx(point, rel=1e-2)  # the brief's acceptance: 1 %
    # against the exact value for this load (cap curvature, a^2/(5R^2) ~ 1e-5 .. 3e-4)
    exact = mean_stress_exact(R, bead.force, bead.contact_radius)
    assert ms["zz"] == pytest.approx(exact, rel=1e-5)
    assert abs(ms["xx"]) < 1e-9 * abs(ms["zz"])


def test_peak_pressure_at_the_pole(bead):
    s = stress_at(bead, 0.0, R)
    assert s[1] == pytest.approx(-bead.peak_pressure, rel=3e-2)  # acceptance: 3 %
    assert s[1] == pytest.approx(-bead.peak_pressure, rel=1e-2)  # measured 0.46 %
    # surface centre of a Hertz contact: sigma_rr = -(1 + 2 nu) p0 / 2 (Johnson eq. 3.45)
    assert s[0] == pytest.approx(-(1 + 2 * NU) / 2 * bead.peak_pressure, rel=1e-2)


def test_axis_stress_matches_hertz_half_space_near_contact(bead):
    a, p0 = bead.contact_radius, bead.peak_pressure
    depth = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0]) * a
    s = stress_at(bead, np.zeros_like(depth), R - depth)
    s_zz, s_rr = hertz_axis_stress(depth, a, p0, NU)
    # the sphere's own (Saint-Venant) field is ~ F/R^2 = (a/R)^2 p0 < 1e-3 p0 here
    np.testing.assert_allclose(s[:, 1], s_zz, atol=0.01 * p0)
    np.testing.assert_allclose(s[:, 0], s_rr, atol=0.015 * p0)
    np.testing.assert_allclose(s[:, 2], s_rr, atol=0.015 * p0)


def test_far_field_is_linear_in_force_but_contact_field_is_not():
    lo = solve_bead_stress(R, E, NU, 1.0)
    hi = solve_bead_stress(R, E, NU, 100.0)
    pts_r, pts_z = np.array([0.0, 0.5e-3, 1.5e-3]), np.array([0.0, 0.5e-3, -0.8e-3])
    per_n_lo = stress_at(lo, pts_r, pts_z) / lo.force
    per_n_hi = stress_at(hi, pts_r, pts_z) / hi.force
    scale = abs(per_n_lo[0, 1])  # |sigma_zz| at the centre, per newton
    # far from the contacts the stress per newton does not depend on F (to ~a^2/R^2;
    # the two solutions are on different meshes, each ~0.5 % accurate in the bulk)
    np.testing.assert_allclose(per_n_hi, per_n_lo, atol=1e-2 * scale)
    # at the pole it scales as p0 / F ~ F^(-2/3)
    pole = stress_at(hi, 0.0, R)[1] / stress_at(lo, 0.0, R)[1]
    assert pole == pytest.approx(100.0 ** (1 / 3), rel=5e-3)


def _mean_error(refine: int, order: int) -> float:
    # coarse bulk (h = R/4 ... R/16 on the arc), so that the geometric error stays above the
    # ~1e-9 floor set by the quadrature of the cap's load moment
    spec = BeadMeshSpec(bulk_size=0.25, refine=refine, order=order)
    bs = solve_bead_stress(R, E, NU, 10.0, spec=spec)
    exact = mean_stress_exact(R, 10.0, bs.contact_radius)
    return abs(mean_stress(bs)["zz"] / exact - 1)


@pytest.mark.parametrize(("order", "expected"), [(2, 4.0), (1, 2.0)])
def test_mean_stress_converges_at_the_geometric_order(order, expected):
    # The Galerkin identity a(u_h, z e_z) = l(z e_z) makes the discrete integral of
    # sigma_zz exact; the mean's error is that of the discrete volume: O(h^4) for curved
    # quadratic elements, O(h^2) for straight ones.
    errs = np.array([_mean_error(k, order) for k in range(3)])
    slope = np.polyfit(np.log(2.0 ** -np.arange(3)), np.log(errs), 1)[0]
    assert slope > expected - 0.3, (slope, errs)
    assert errs[0] < 1e-2  # measured 5.0e-6 (curved), 8.9e-3 (straight) at h = R/4


@pytest.mark.slow
def test_pole_stress_converges():
    errs = []
    for k in range(4):
        bs = solve_bead_stress(R, E, NU, 10.0, refine=k)
        errs.append(abs(stress_at(bs, 0.0, R)[1] / bs.peak_pressure + 1))
    slope = np.polyfit(np.log(2.0 ** -np.arange(4)), np.log(errs), 1)[0]
    assert slope > 1.5, (slope, errs)
    assert errs[-1] < 2e-4
