"""Tests of post-processing (msens.field.post)."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.field.post import energy, field_strength, flux_density, flux_linkage, force_z
from msens.field.regions import Air, CurrentRegion, NonlinearSoft, PermanentMagnet
from msens.field.solve import MagnetostaticProblem, incremental, solve
from msens.field.verification_geometry import Part, build_mesh
from msens.params.materials import STEEL_1018_BH
from msens.params.units import MU0

STEEL = NonlinearSoft(STEEL_1018_BH)
R_BEAD = 2.38e-3


@pytest.fixture(scope="module")
def beads_solution():
    """Two steel beads (0.2 mm gap) on the axis inside a ring magnet, plus a coil."""
    pitch = 2 * R_BEAD + 0.2e-3
    parts = [Part("lower", "sphere", (R_BEAD, -pitch / 2), R_BEAD / 6),
             Part("upper", "sphere", (R_BEAD, pitch / 2), R_BEAD / 6),
             Part("coil", "rect", (4e-3, 6e-3, -3.5e-3, 3.5e-3), 0.6e-3),
             Part("magnet", "rect", (8e-3, 14e-3, 1e-3, 7e-3), 0.8e-3)]
    mesh = build_mesh(parts, 0.06, 0.01, grading=0.3,
                      sizing=[Part("gap", "rect", (0.0, 1e-3, -0.2e-3, 0.2e-3), 0.08e-3)])
    regions = {"lower": STEEL, "upper": STEEL, "coil": CurrentRegion(0.0),
               "magnet": PermanentMagnet(1.24, 1.05), "air": Air()}
    return solve(MagnetostaticProblem(mesh, regions))


def test_axis_value_is_the_limit_of_nearby_values(beads_solution):
    z = np.linspace(-4e-3, 4e-3, 9)
    on = flux_density(beads_solution, 0.0, z)
    near = flux_density(beads_solution, 1e-8, z)
    np.testing.assert_allclose(on, near, atol=1e-5 * np.abs(on).max())
    assert np.all(on[:, 0] == 0.0)  # B_r vanishes on the axis


def test_output_shape_follows_broadcast_inputs(beads_solution):
    r = np.linspace(0.0, 3e-3, 4)[:, None]
    z = np.linspace(-1e-3, 1e-3, 5)[None, :]
    assert flux_density(beads_solution, r, z).shape == (4, 5, 2)
    assert field_strength(beads_solution, r, z).shape == (4, 5, 2)


def test_field_strength_follows_each_constitutive_law(beads_solution):
    pts_air = (np.array([3e-3, 7e-3]), np.array([0.0, -5e-3]))
    b = flux_density(beads_solution, *pts_air)
    np.testing.assert_allclose(field_strength(beads_solution, *pts_air), b / MU0, rtol=1e-12)
    r, z = 11e-3, 4e-3  # inside the magnet: H = (B - Br e_z)/(mu0 mu_rec)
    b = flux_density(beads_solution, r, z)
    h = field_strength(beads_solution, r, z)
    np.testing.assert_allclose(h, (b - [0.0, 1.24]) / (MU0 * 1.05), rtol=1e-10)
    b = flux_density(beads_solution, 1e-3, R_BEAD)  # steel: H || B, |H| = H(|B|)
    h = field_strength(beads_solution, 1e-3, R_BEAD)
    assert abs(b[0] * h[1] - b[1] * h[0]) < 1e-12 * np.hypot(*b) * np.hypot(*h)
    assert np.hypot(*h) < np.hypot(*b) / MU0 / 50  # highly permeable


def test_points_outside_the_mesh_are_input_errors(beads_solution):
    with pytest.raises(InputError, match="outside the mesh"):
        flux_density(beads_solution, 1.0, 0.0)
    with pytest.raises(InputError, match="r >= 0"):
        flux_density(beads_solution, -1e-3, 0.0)


def test_maxwell_and_virtual_work_agree_on_nonlinear_beads(beads_solution):
    f_mx = force_z(beads_solution, ["upper"], method="maxwell")
    f_vw = force_z(beads_solution, ["upper"], method="virtual_work")
    assert f_vw == pytest.approx(f_mx, rel=2e-2)
    assert abs(f_mx) > 1e-3  # a real force (N), not numerical noise
    # the beads' mutual attraction cancels in the pair: F(pair) = F(upper) + F(lower), each
    # from its own eggshell function
    both = force_z(beads_solution, ["lower", "upper"])
    lower = force_z(beads_solution, ["lower"])
    assert both == pytest.approx(f_mx + lower, rel=2e-2, abs=1e-3 * abs(f_mx))


def test_force_needs_air_around_the_bodies(beads_solution):
    with pytest.raises(InputError, match="not a region"):
        force_z(beads_solution, ["nope"])
    with pytest.raises(InputError, match="winding"):
        force_z(beads_solution, ["coil"])
    inc = incremental(beads_solution, {"coil": CurrentRegion(1e6)})
    with pytest.raises(InputError, match="bias solution"):
        force_z(inc, ["upper"])


def test_touching_bodies_are_rejected():
    parts = [Part("a", "rect", (0.0, 1e-3, -1e-3, 0.0), 2e-4),
             Part("b", "rect", (0.0, 1e-3, 0.0, 1e-3), 2e-4)]
    mesh = build_mesh(parts, 0.02, 0.004)
    sol = solve(MagnetostaticProblem(mesh, {"a": PermanentMagnet(1.0), "b": STEEL,
                                            "air": Air()}))
    with pytest.raises(InputError, match="touch non-air parts"):
        force_z(sol, ["b"])


def test_incremental_energy_equals_half_l_i_squared(beads_solution):
    turns, area = 300, 2e-3 * 7e-3
    inc = incremental(beads_solution, {"coil": CurrentRegion(turns / area)})
    assert 2 * energy(inc) == pytest.approx(flux_linkage(inc, "coil", turns), rel=1e-9)


def test_flux_linkage_rejects_bad_input(beads_solution):
    with pytest.raises(InputError, match="turns"):
        flux_linkage(beads_solution, "coil", 0)
    with pytest.raises(InputError, match="not a subdomain"):
        flux_linkage(beads_solution, "winding", 10)


