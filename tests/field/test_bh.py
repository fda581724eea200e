"""Tests of the monotone B-H interpolation (msens.field.bh)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from msens.errors import InputError
from msens.field.bh import monotone_bh
from msens.params.materials import STEEL_1018_BH, BHCurve
from msens.params.units import MU0

LAW = monotone_bh(STEEL_1018_BH)


def test_interpolant_passes_through_the_table():
    np.testing.assert_allclose(LAW.field_strength(STEEL_1018_BH.b), STEEL_1018_BH.h,
                               rtol=1e-12, atol=1e-9)


def test_h_of_b_is_strictly_increasing_over_and_beyond_the_table():
    b = np.linspace(0.0, 4.0, 20001)
    assert np.all(np.diff(LAW.field_strength(b)) > 0)
    assert np.all(LAW.differential_reluctivity(b) > 0)


def test_extrapolation_has_slope_mu0_and_is_continuous():
    b_n, h_n = STEEL_1018_BH.b[-1], STEEL_1018_BH.h[-1]
    for db in (1e-3, 0.5, 2.0):
        assert LAW.field_strength(np.array(b_n + db)) == pytest.approx(h_n + db / MU0, rel=1e-12)
    left = LAW.field_strength(np.array(b_n - 1e-9))
    assert float(left) == pytest.approx(h_n, abs=1e-2)  # continuous: slope ~ 8e5 A/m/T


@given(st.floats(min_value=1e-3, max_value=3.5))
def test_energy_density_derivative_is_h(b):
    eps = 1e-6
    dw = (LAW.energy_density(np.array(b + eps)) - LAW.energy_density(np.array(b - eps))) / (2 * eps)
    assert float(dw) == pytest.approx(float(LAW.field_strength(np.array(b))), rel=1e-5, abs=1e-3)


@given(st.floats(min_value=1e-2, max_value=3.5))
def test_reluctivity_derivative_matches_finite_difference(b):
    b2, eps = b * b, 1e-7 * b * b
    fd = (LAW.reluctivity(np.sqrt(b2 + eps)) - LAW.reluctivity(np.sqrt(b2 - eps))) / (2 * eps)
    assert float(LAW.reluctivity_derivative(np.array(b2))) == pytest.approx(float(fd), rel=1e-4,
                                                                             abs=1e-2)


def test_reluctivity_at_zero_is_the_initial_slope():
    assert float(LAW.reluctivity(np.array(0.0))) == pytest.approx(
        float(LAW.reluctivity(np.array(1e-7))), rel=1e-5)


def test_non_monotone_curve_is_rejected():
    bad = BHCurve("bad", np.array([0.0, 1.0, 0.9]), np.array([0.0, 10.0, 20.0]), "test")
    with pytest.raises(InputError, match="strictly increasing"):
        monotone_bh(bad)


def test_curve_must_start_at_origin():
    bad = BHCurve("bad", np.array([0.1, 1.0, 1.5]), np.array([0.0, 10.0, 20.0]), "test")
    with pytest.raises(InputError, match=r"start at \(0, 0\)"):
        monotone_bh(bad)
