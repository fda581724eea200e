"""Tests of the solver (msens.field.solve): linear, Newton, incremental, errors."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.field.post import flux_density, flux_linkage
from msens.field.regions import Air, CurrentRegion, LinearMagnetic, NonlinearSoft, PermanentMagnet
from msens.field.solve import FieldSolveError, MagnetostaticProblem, incremental, solve
from msens.field.verification_geometry import Part, build_mesh, rect_mesh
from msens.field.verify import nonlinear_sphere_exact
from msens.params.materials import STEEL_1018_BH

STEEL = NonlinearSoft(STEEL_1018_BH)


@pytest.fixture(scope="module")
def coil_mesh():
    return rect_mesh("coil", 0.01, 0.02, 0.02, 0.2, 2e-3, 0.03)


@pytest.fixture(scope="module")
def rod_mesh():
    """A steel rod in a coil, with a ring magnet around both (the sensor in miniature)."""
    parts = [Part("rod", "rect", (0.0, 2.4e-3, -10e-3, 10e-3), 0.6e-3),
             Part("coil", "rect", (4e-3, 6e-3, -3.5e-3, 3.5e-3), 0.6e-3),
             Part("magnet", "rect", (8e-3, 14e-3, -4e-3, 4e-3), 1e-3)]
    return build_mesh(parts, 0.08, 0.01, grading=0.3)


def rod_regions(remanence=1.24, coil_j=0.0):
    return {"rod": STEEL, "coil": CurrentRegion(coil_j), "magnet": PermanentMagnet(remanence, 1.05),
            "air": Air()}


def test_every_subdomain_needs_a_region(coil_mesh):
    with pytest.raises(InputError, match="missing"):
        MagnetostaticProblem(coil_mesh, {"coil": CurrentRegion(1.0)})


def test_unknown_outer_boundary_is_rejected(coil_mesh):
    with pytest.raises(InputError, match="outer boundary 'box'"):
        MagnetostaticProblem(coil_mesh, {"coil": CurrentRegion(1.0), "air": Air()}, outer=("box",))


def test_linear_solution_scales_with_current(coil_mesh):
    s1 = solve(MagnetostaticProblem(coil_mesh, {"coil": CurrentRegion(1e6), "air": Air()}))
    s3 = solve(MagnetostaticProblem(coil_mesh, {"coil": CurrentRegion(3e6), "air": Air()}))
    assert s1.iterations == 1 and s1.residuals[0] < 1e-10
    np.testing.assert_allclose(s3.a, 3 * s1.a, rtol=1e-10, atol=1e-14)


def test_newton_converges_quadratically_on_the_rod(rod_mesh):
    sol = solve(MagnetostaticProblem(rod_mesh, rod_regions()))
    res = np.array(sol.residuals)
    assert sol.iterations <= 15 and res[-1] <= 1e-8
    # superlinear at the end: the last reduction beats the first clearly
    assert res[-1] / res[-2] < 0.1 * res[1] / res[0]
    bz = flux_density(sol, 0.0, 0.0)[1]
    assert 1.0 < abs(bz) < 2.4  # a saturating steel rod between the magnet's poles


def test_nonlinear_sphere_matches_exact_uniform_solution():
    from msens.field.verification_geometry import sphere_mesh

    mesh = sphere_mesh(0.01, 0.15, 0.01 / 8, h_far=0.02)
    for b0 in (0.2, 0.9):
        sol = solve(MagnetostaticProblem(mesh, {"sphere": STEEL, "air": Air()},
                                         background_field=b0))
        b_ref, _ = nonlinear_sphere_exact(b0)
        assert flux_density(sol, 0.0, 0.0)[1] == pytest.approx(b_ref, rel=3e-3)


def test_newton_failure_raises_with_history(rod_mesh):
    with pytest.raises(FieldSolveError) as info:
        solve(MagnetostaticProblem(rod_mesh, rod_regions()), tol=1e-14, max_iter=2)
    assert len(info.value.residuals) == 2
    assert "did not converge" in str(info.value)


def test_incremental_equals_central_difference_of_nonlinear_solves(rod_mesh):
    n_turns, area = 500, 2e-3 * 7e-3
    j1 = n_turns / area  # 1 A
    bias = solve(MagnetostaticProblem(rod_mesh, rod_regions()), tol=1e-12, max_iter=30)
    inc = incremental(bias, {"coil": CurrentRegion(j1)})
    l_inc = flux_linkage(inc, "coil", n_turns)
    eps = 1e-3
    lam = [flux_linkage(solve(MagnetostaticProblem(rod_mesh, rod_regions(coil_j=s * eps * j1)),
                              initial=bias.a, tol=1e-13, max_iter=30), "coil", n_turns)
           for s in (+1, -1)]
    l_fd = (lam[0] - lam[1]) / (2 * eps)
    assert l_inc == pytest.approx(l_fd, rel=1e-5)
    # saturation lowers the incremental inductance below the unbiased one
    unbiased = incremental(solve(MagnetostaticProblem(rod_mesh, rod_regions(remanence=0.0))),
                           {"coil": CurrentRegion(j1)})
    assert l_inc < flux_linkage(unbiased, "coil", n_turns)


def test_incremental_of_linear_problem_is_the_linear_solve(rod_mesh):
    regions = {"rod": LinearMagnetic(500.0), "coil": CurrentRegion(0.0),
               "magnet": PermanentMagnet(1.0, 1.05), "air": Air()}
    bias = solve(MagnetostaticProblem(rod_mesh, regions))
    inc = incremental(bias, {"coil": CurrentRegion(2e6)})
    direct = solve(MagnetostaticProblem(rod_mesh, {**regions, "coil": CurrentRegion(2e6),
                                                   "magnet": PermanentMagnet(0.0, 1.05)}))
    np.testing.assert_allclose(inc.a, direct.a, rtol=1e-9, atol=1e-12 * np.abs(direct.a).max())


def test_incremental_source_must_be_a_winding(rod_mesh):
    bias = solve(MagnetostaticProblem(rod_mesh, rod_regions(remanence=0.0)))
    with pytest.raises(InputError, match="not a CurrentRegion"):
        incremental(bias, {"rod": CurrentRegion(1.0)})
