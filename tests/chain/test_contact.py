"""Hertz prefactors against the paper's Eq. 2 and 7 and their limits."""

import numpy as np
import pytest

from msens.mechanics.hertz import (
    effective_modulus,
    hertz_energy,
    hertz_sphere_flat,
    hertz_sphere_sphere,
)

E, NU, R = 200e9, 0.29, 2.38e-3


def test_identical_spheres_match_paper_eq2():
    expected = E * np.sqrt(2 * R) / (3 * (1 - NU**2))
    assert hertz_sphere_sphere(E, NU, R, E, NU, R) == pytest.approx(expected, rel=1e-14)


def test_sphere_on_flat_matches_paper_eq7():
    E_w, nu_w = 210e9, 0.3
    expected = 4 * np.sqrt(R) / 3 / ((1 - NU**2) / E + (1 - nu_w**2) / E_w)
    assert hertz_sphere_flat(E, NU, R, E_w, nu_w) == pytest.approx(expected, rel=1e-14)


def test_flat_is_the_large_radius_limit_of_a_sphere():
    big = hertz_sphere_sphere(E, NU, R, 63e9, 0.31, 1e8 * R)
    assert big == pytest.approx(hertz_sphere_flat(E, NU, R, 63e9, 0.31), rel=1e-8)


def test_symmetric_and_broadcasting():
    a = hertz_sphere_sphere(E, NU, R, 63e9, 0.31, 2 * R)
    b = hertz_sphere_sphere(63e9, 0.31, 2 * R, E, NU, R)
    assert a == pytest.approx(b, rel=1e-15)
    radii = np.array([1e-3, 2e-3, 3e-3])
    out = hertz_sphere_flat(E, NU, radii, E, NU)
    assert out.shape == (3,)
    np.testing.assert_allclose(out / np.sqrt(radii), out[0] / np.sqrt(radii[0]), rtol=1e-14)
    assert effective_modulus(E, NU, E, NU) == pytest.approx(E / (2 * (1 - NU**2)), rel=1e-15)


def test_energy_is_the_work_of_the_force():
    A, d = 5e9, 1e-6
    h = 1e-12
    dU = (hertz_energy(A, d + h) - hertz_energy(A, d - h)) / (2 * h)
    assert dU == pytest.approx(A * d**1.5, rel=1e-6)
    assert hertz_energy(A, -1e-6) == 0.0
