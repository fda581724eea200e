"""Unit tests of msens.mechanics.beadstress and msens.mechanics.beadmesh: closed forms, shapes,
symmetry, input."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.mechanics.beadmesh import BeadMeshSpec, bead_section_mesh
from msens.mechanics.beadstress import hertz_axis_stress, hertz_contact, solve_bead_stress
from msens.mechanics.stress_sampling import mean_stress, mean_stress_exact, stress_along, stress_at
from msens.params.materials import BEAD_STEEL

R = 2.38e-3
E, NU = BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio


@pytest.fixture(scope="module")
def bead():
    return solve_bead_stress(R, E, NU, 10.0)


def test_hertz_contact_is_consistent_with_the_chain_contact_law():
    # two equal spheres: F = A delta^(3/2), A = E sqrt(2R) / (3 (1 - nu^2)) (design.md §5),
    # and the approach of the centres is delta = a^2 / R* with R* = R/2
    F = 37.0
    a, p0 = hertz_contact(R, E, NU, F)
    delta = a**2 / (R / 2)
    A = E * np.sqrt(2 * R) / (3 * (1 - NU**2))
    assert A * delta**1.5 == pytest.approx(F, rel=1e-12)
    assert p0 == pytest.approx(1.5 * F / (np.pi * a**2), rel=1e-12)  # peak = 1.5 x mean


def test_hertz_contact_scaling_with_force():
    a1, p1 = hertz_contact(R, E, NU, 1.0)
    a8, p8 = hertz_contact(R, E, NU, 8.0)
    assert a8 / a1 == pytest.approx(2.0, rel=1e-12)  # a ~ F^(1/3)
    assert p8 / p1 == pytest.approx(2.0, rel=1e-12)  # p0 ~ F^(1/3)


@pytest.mark.parametrize("args", [(0.0, E, NU, 1.0), (R, -1.0, NU, 1.0), (R, E, 0.5, 1.0),
                                  (R, E, NU, 0.0), (R, E, NU, np.nan)])
def test_hertz_contact_rejects_bad_input(args):
    with pytest.raises(InputError):
        hertz_contact(*args)


def test_hertz_axis_stress_limits():
    p0, a = 1e9, 1e-5
    s_zz, s_rr = hertz_axis_stress(np.array([0.0, 1e3 * a]), a, p0, NU)
    # surface: sigma_zz = -p0, sigma_rr = -(1 + 2 nu) p0 / 2 (Johnson 1985, eq. 3.45)
    assert s_zz[0] == pytest.approx(-p0)
    assert s_rr[0] == pytest.approx(-(1 + 2 * NU) / 2 * p0)
    assert abs(s_zz[1]) < 1e-5 * p0 and abs(s_rr[1]) < 1e-5 * p0


def test_mean_stress_exact_tends_to_point_load_value():
    point = mean_stress_exact(R, 1.0)
    assert point == pytest.approx(-3 / (2 * np.pi * R**2))
    a = 0.03 * R
    # cap curvature lowers the magnitude by ~ a^2 / (5 R^2)
    assert mean_stress_exact(R, 1.0, a) / point == pytest.approx(1 - 0.2 * 0.03**2, rel=1e-6)


def test_mesh_boundaries_and_grading():
    a = 0.01 * R
    m = bead_section_mesh(R, a, BeadMeshSpec())
    assert set(m.boundaries) == {"axis", "equator", "contact", "free"}
    f = m.facets
    mid = m.p[:, f[:, m.boundaries["contact"]]].mean(axis=1)
    assert np.all(mid[0] < a) and len(m.boundaries["contact"]) >= 4
    # pole at the origin of the mesh coordinates, equator at s = -R
    assert m.p[1].max() == pytest.approx(0.0, abs=1e-15)
    assert m.p[1].min() == pytest.approx(-R, rel=1e-12)


@pytest.mark.parametrize("kw", [{"contact_elements": 0}, {"grading": -1.0}, {"bulk_size": 2.0},
                                {"refine": -1}, {"order": 3}])
def test_mesh_spec_rejects_bad_values(kw):
    with pytest.raises(InputError):
        BeadMeshSpec(**kw)


def test_mesh_rejects_large_contact():
    with pytest.raises(InputError):
        bead_section_mesh(R, 0.6 * R)


def test_stress_at_shapes_and_mirror_symmetry(bead):
    r = np.array([[0.0, 0.3e-3], [1.0e-3, 2.0e-3]])
    z = np.array([[0.5e-3, 1.1e-3], [-0.7e-3, 0.2e-3]])
    up = stress_at(bead, r, z)
    down = stress_at(bead, r, -z)
    assert up.shape == (2, 2, 4)
    np.testing.assert_allclose(down[..., :3], up[..., :3], rtol=1e-12)
    np.testing.assert_allclose(down[..., 3], -up[..., 3], rtol=1e-12)
    assert stress_at(bead, 0.0, 0.0).shape == (4,)


def test_stress_at_points_on_the_surface_and_axis(bead):
    th = np.linspace(0.0, np.pi, 13)
    s = stress_at(bead, R * np.sin(th), R * np.cos(th))  # the whole meridian arc
    assert np.all(np.isfinite(s))
    # on the axis sigma_rr = sigma_thth and sigma_rz = 0 (up to the discretisation)
    axis = stress_at(bead, np.zeros(5), np.linspace(-0.9, 0.9, 5) * R)
    scale = abs(mean_stress_exact(R, bead.force))
    np.testing.assert_allclose(axis[:, 0], axis[:, 2], atol=1e-2 * scale)
    # relative to the local stress, which near the contacts is ~100x the mean
    assert np.all(np.abs(axis[:, 3]) < 0.03 * np.abs(axis[:, 1]))


def test_stress_at_rejects_points_outside(bead):
    with pytest.raises(InputError):
        stress_at(bead, 0.0, 1.01 * R)
    with pytest.raises(InputError):
        stress_at(bead, -1e-4, 0.0)


def test_stress_along_projections(bead):
    r, z = 0.4e-3, 0.9e-3
    s = stress_at(bead, r, z)
    assert stress_along(bead, r, z, [0.0, 2.0]) == pytest.approx(s[1])
    assert stress_along(bead, r, z, [1.0, 0.0]) == pytest.approx(s[0])
    h = np.array([1.0, 1.0]) / np.sqrt(2)
    assert stress_along(bead, r, z, h) == pytest.approx(0.5 * (s[0] + s[1]) + s[3])
    dev = stress_along(bead, r, z, [0.0, 1.0], kind="deviatoric")
    assert dev == pytest.approx(1.5 * (s[1] - s[:3].sum() / 3))
    with pytest.raises(InputError):
        stress_along(bead, r, z, [0.0, 0.0])
    with pytest.raises(InputError):
        stress_along(bead, r, z, [0.0, 1.0], kind="vonmises")


def test_mean_stress_keys_and_transverse_balance(bead):
    ms = mean_stress(bead)
    assert set(ms) == {"zz", "xx", "rr", "tt", "rz", "volume"}
    assert abs(ms["xx"]) < 1e-9 * abs(ms["zz"])  # Cartesian transverse mean vanishes
    assert ms["rr"] == pytest.approx(-ms["tt"], rel=1e-9)
    assert ms["volume"] == pytest.approx(4 / 3 * np.pi * R**3, rel=1e-5)
