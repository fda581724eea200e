"""Tests of the Jiles–Atherton–Sablik anhysteretic law (msens.magnetics.magnetoelastic)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens.errors import InputError
from msens.magnetics.magnetoelastic import (
    DEFAULT_STEEL,
    JilesAthertonSablik,
    PiezomagneticCoefficient,
    anhysteretic_magnetisation,
    differential_susceptibility,
    equivalent_uniaxial_stress,
    flux_density,
    langevin,
    langevin_derivative,
    piezomagnetic_coefficient,
    stress_sensitivity,
    unique_stress_range,
)
from msens.params.magnetostriction_data import JA_DEFAULTS_STEEL
from msens.params.units import MU0

LAW = DEFAULT_STEEL
LAWS = [DEFAULT_STEEL, JA_DEFAULTS_STEEL]


# --- Langevin function ----------------------------------------------------------------------

def test_langevin_matches_high_precision_on_both_branches():
    mpmath = pytest.importorskip("mpmath")
    mpmath.mp.dps = 40
    # both sides of the series/closed-form switch at |x| = 1, and far out
    x = np.array([1e-12, 1e-6, 1e-3, 0.1, 0.5, 0.999, 1.0, 1.001, 2.0, 30.0, 700.0])
    x = np.concatenate([-x, x])
    ref_l = np.array([float(mpmath.coth(v) - 1 / mpmath.mpf(v)) for v in x])
    ref_d = np.array([float(1 / mpmath.mpf(v) ** 2 - 1 / mpmath.sinh(v) ** 2) for v in x])
    np.testing.assert_allclose(langevin(x), ref_l, rtol=1.5e-15, atol=0)
    np.testing.assert_allclose(langevin_derivative(x), ref_d, rtol=1.5e-15, atol=0)


def test_langevin_limits_without_warnings():
    # pytest turns warnings into errors: no overflow in sinh/exp at huge arguments
    x = np.array([0.0, 1e3, -1e3, 1e300])
    np.testing.assert_array_equal(langevin(x)[0], 0.0)
    assert langevin_derivative(0.0) == pytest.approx(1 / 3, rel=1e-15)
    np.testing.assert_allclose(langevin(x[1:3]), [1 - 1e-3, -(1 - 1e-3)], rtol=1e-15)
    np.testing.assert_allclose(langevin_derivative(x[1:3]), [1e-6, 1e-6], rtol=1e-12)
    assert langevin(1e300) == 1.0


# --- M(H, σ) ----------------------------------------------------------------------------------

@pytest.mark.parametrize("law", LAWS)
def test_magnetisation_monotone_odd_bounded_and_saturating(law):
    h = np.concatenate([[0.0], np.geomspace(1e-3, 1e8, 400)])
    m = anhysteretic_magnetisation(law, h)
    assert m[0] == 0.0
    assert np.all(np.diff(m) > 0.0)
    assert np.all(m < law.Ms)
    np.testing.assert_array_equal(anhysteretic_magnetisation(law, -h), -m)
    # L(x) -> 1 - 1/x: at H = 1e8 A/m, 1 - M/Ms = a/H_e to 1e-6 relative
    assert 1 - m[-1] / law.Ms == pytest.approx(law.a / (1e8 + law.alpha * m[-1]), rel=1e-6)
    # initial susceptibility of the mean-field Langevin law
    assert m[1] / h[1] == pytest.approx(law.Ms / (3 * law.a - law.alpha * law.Ms), rel=1e-9)


@pytest.mark.parametrize("law", LAWS)
def test_solution_satisfies_the_implicit_equation(law):
    # the whole admissible stress range, fields from 1e-3 A/m to 1e6 A/m
    rng = np.random.default_rng(1)
    n = 20000
    lo, hi = unique_stress_range(law)
    h = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-3, 6, n)
    s = rng.uniform(lo, hi, n)
    m = anhysteretic_magnetisation(law, h, s)
    g1 = law.gamma11 + law.gamma12 * s
    g2 = law.gamma21 + law.gamma22 * s
    dlam_dm = 2 * g1 * m + 4 * g2 * m**3
    he = h + law.alpha * m + law.coupling * s / MU0 * dlam_dm
    np.testing.assert_allclose(m, law.Ms * langevin(he / law.a), rtol=1e-12, atol=1e-9)


def test_shapes_broadcast():
    h = np.array([[1e2], [1e3], [1e4]])
    s = np.array([-1e7, 0.0, 1e7, 5e7])
    for f in (anhysteretic_magnetisation, differential_susceptibility, stress_sensitivity,
              piezomagnetic_coefficient, flux_density):
        assert f(LAW, h, s).shape == (3, 4)
    assert anhysteretic_magnetisation(LAW, 1e3).shape == ()


def test_flux_density_is_mu0_h_plus_m():
    h = np.geomspace(1.0, 3e5, 50)
    s = 2e7
    np.testing.assert_allclose(flux_density(LAW, h, s),
                               MU0 * (h + anhysteretic_magnetisation(LAW, h, s)), rtol=1e-15)


# --- derivatives --------------------------------------------------------------------------

H_PTS = np.array([50.0, 500.0, 1.5e3, 3e3, 8e3, 2e4, 6e4])
S_PTS = np.array([-5e7, -1e7, 0.0, 2e7, 1e8])


@pytest.mark.parametrize("law", LAWS)
def test_stress_sensitivity_matches_finite_differences(law):
    h, s = np.meshgrid(H_PTS, S_PTS)
    ds = 5e3  # Pa; truncation ~ (ds/1e7)^2 and rounding ~ 1e-10/dM, both < 1e-7
    fd = (anhysteretic_magnetisation(law, h, s + ds)
          - anhysteretic_magnetisation(law, h, s - ds)) / (2 * ds)
    np.testing.assert_allclose(stress_sensitivity(law, h, s), fd, rtol=1e-6)


@pytest.mark.parametrize("law", LAWS)
def test_susceptibility_matches_finite_differences(law):
    h, s = np.meshgrid(H_PTS, S_PTS)
    dh = 1e-4 * h
    fd = (anhysteretic_magnetisation(law, h + dh, s)
          - anhysteretic_magnetisation(law, h - dh, s)) / (2 * dh)
    np.testing.assert_allclose(differential_susceptibility(law, h, s), fd, rtol=1e-6)


def test_piezomagnetic_coefficient_is_mu0_dm_dsigma_and_odd_in_h():
    h = np.linspace(-3e4, 3e4, 61)
    d = piezomagnetic_coefficient(LAW, h, 1e7)
    np.testing.assert_allclose(d, MU0 * stress_sensitivity(LAW, h, 1e7), rtol=1e-15)
    np.testing.assert_allclose(d, -d[::-1], rtol=1e-13, atol=1e-25)
    call = PiezomagneticCoefficient(LAW, sigma=1e7)
    np.testing.assert_array_equal(call(h.reshape(61, 1)), d.reshape(61, 1))


@pytest.mark.parametrize("sigma", [-8e7, -1e7, 0.0, 1e7, 2e8])
def test_no_bias_field_no_signal(sigma):
    # λ is even in M, so with the magnet off (H = 0, M = 0) stress does not magnetise
    assert anhysteretic_magnetisation(LAW, 0.0, sigma) == 0.0
    assert stress_sensitivity(LAW, 0.0, sigma) == 0.0
    assert piezomagnetic_coefficient(LAW, 0.0, sigma) == 0.0


# --- input checks ---------------------------------------------------------------------------

def test_bad_inputs_raise_input_error():
    lo, hi = unique_stress_range(LAW)
    with pytest.raises(InputError, match="outside"):
        anhysteretic_magnetisation(LAW, 1e3, 1.01 * lo)
    with pytest.raises(InputError, match="outside"):
        stress_sensitivity(LAW, [1e3, 2e3], [0.0, 1.01 * hi])
    with pytest.raises(InputError, match="finite"):
        anhysteretic_magnetisation(LAW, np.nan)
    with pytest.raises(InputError, match="finite"):
        anhysteretic_magnetisation(LAW, 1.0, np.inf)
    with pytest.raises(InputError, match="a must be > 0"):
        dataclasses.replace(LAW, a=0.0)
    with pytest.raises(InputError, match="single-valued"):
        dataclasses.replace(LAW, alpha=3 * LAW.a / LAW.Ms)
    with pytest.raises(InputError, match="Ms"):
        JilesAthertonSablik(-1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.5, "x")


# --- equivalent uniaxial stress -----------------------------------------------------------

def test_equivalent_stress_elementary_states():
    s0 = 3e7
    ez = np.array([0.0, 0.0, 1.0])
    along = np.diag([0.0, 0.0, s0])
    across = np.diag([s0, 0.0, 0.0])
    assert equivalent_uniaxial_stress(along, ez) == pytest.approx(s0, rel=1e-15)
    assert equivalent_uniaxial_stress(across, ez) == pytest.approx(-s0 / 2, rel=1e-15)
    assert equivalent_uniaxial_stress(-5e8 * np.eye(3), ez) == pytest.approx(0.0, abs=1e-6)
    # the field's length does not matter, a zero field gives 0
    assert equivalent_uniaxial_stress(along, 7.0 * ez) == pytest.approx(s0, rel=1e-15)
    assert equivalent_uniaxial_stress(along, np.zeros(3)) == 0.0


def test_equivalent_stress_is_rotation_invariant_and_batched():
    rng = np.random.default_rng(7)
    a = rng.normal(size=(20, 3, 3)) * 1e7
    sig = a + np.swapaxes(a, -1, -2)
    h = rng.normal(size=(20, 3))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    sig_r = q @ sig @ q.T
    h_r = h @ q.T
    np.testing.assert_allclose(equivalent_uniaxial_stress(sig_r, h_r),
                               equivalent_uniaxial_stress(sig, h), rtol=1e-12, atol=1e-3)
    assert equivalent_uniaxial_stress(sig, h).shape == (20,)


def test_axisymmetric_components_match_full_tensor():
    rng = np.random.default_rng(3)
    comp = rng.normal(size=(5, 4)) * 1e7  # [srr, szz, stt, srz]
    hrz = rng.normal(size=(5, 2))
    tensor = np.zeros((5, 3, 3))  # basis (r, theta, z)
    tensor[:, 0, 0], tensor[:, 2, 2], tensor[:, 1, 1] = comp[:, 0], comp[:, 1], comp[:, 2]
    tensor[:, 0, 2] = tensor[:, 2, 0] = comp[:, 3]
    h3 = np.stack([hrz[:, 0], np.zeros(5), hrz[:, 1]], axis=-1)
    np.testing.assert_allclose(equivalent_uniaxial_stress(comp, hrz),
                               equivalent_uniaxial_stress(tensor, h3), rtol=1e-13)


def test_equivalent_stress_bad_shapes():
    with pytest.raises(InputError, match="shape"):
        equivalent_uniaxial_stress(np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(InputError, match="h_dir"):
        equivalent_uniaxial_stress(np.zeros(4), np.zeros(3))
    with pytest.raises(InputError, match="h_dir"):
        equivalent_uniaxial_stress(np.zeros((3, 3)), np.zeros(2))
