"""Tests of the long-wavelength speed formulas (msens.mechanics.longwave)."""

from __future__ import annotations

import numpy as np
import pytest

from msens.mechanics.longwave import (
    soliton_speed_precompressed,
    soliton_speed_uncompressed,
    sound_speed,
)

# Paper beads (§2): 4.76 mm, E 200 GPa, nu 0.29, rho 7970 kg/m^3.
A_DIAM, E, NU, RHO = 4.76e-3, 200e9, 0.29, 7970.0


def test_sound_speed_equals_linearised_hertz_chain():
    # c0 = a sqrt(k/m), k = dF/d(delta) = (3/2) A^(2/3) F0^(1/3), A = E sqrt(a) / (3 (1-nu^2)).
    F0 = np.array([0.01, 0.3, 1.8, 50.0])
    A = E * np.sqrt(A_DIAM) / (3 * (1 - NU**2))
    m = RHO * np.pi * A_DIAM**3 / 6
    exact = A_DIAM * np.sqrt(1.5 * A ** (2 / 3) * F0 ** (1 / 3) / m)
    # The paper's 0.9314 is the exact (81/(4 pi^3))^(1/6) rounded: 5e-5 relative.
    np.testing.assert_allclose(sound_speed(F0, A_DIAM, E, NU, RHO), exact, rtol=1e-4)


def test_precompressed_tends_to_sound_speed_and_is_continuous_at_fr_1():
    F0 = 1.8
    c0 = sound_speed(F0, A_DIAM, E, NU, RHO)
    assert soliton_speed_precompressed(F0, F0, A_DIAM, E, NU, RHO) == pytest.approx(c0, rel=1e-15)
    # Both branches (series for |f_r - 1| < 1e-4, closed form beyond) match the hand-derived
    # expansion V/c0 = 1 + e/6 + e^2/36 + O(e^3), e = f_r^(1/3) - 1.
    fr = np.array([1 + 1e-7, 1 + 0.999e-4, 1 + 1.001e-4, 1 + 1e-3])
    e = fr ** (1 / 3) - 1
    v = soliton_speed_precompressed(fr * F0, F0, A_DIAM, E, NU, RHO) / c0
    np.testing.assert_allclose(v, 1 + e / 6 + e**2 / 36, rtol=1e-9, atol=0)


def test_precompressed_tends_to_uncompressed_for_large_force_ratio():
    F_m = 20.0
    F0 = F_m * 1e-12
    v_pre = soliton_speed_precompressed(F_m, F0, A_DIAM, E, NU, RHO)
    v_un = soliton_speed_uncompressed(F_m, A_DIAM, E, NU, RHO)
    # Leading corrections are O(f_r^(-2/3)) = 1e-8 plus the rounding of the prefactors (2e-6).
    assert v_pre == pytest.approx(v_un, rel=1e-5)


def test_uncompressed_scaling_and_paper_magnitude():
    F = np.array([1.0, 64.0])
    v = soliton_speed_uncompressed(F, A_DIAM, E, NU, RHO)
    assert v[1] / v[0] == pytest.approx(2.0, rel=1e-14)  # F^(1/6)
    # Paper chain: bead 13 -> 18 is 5 diameters (23.8 mm) traversed in ~50 us, i.e. ~480 m/s
    # for pulses of a few tens of N; the formula must give that magnitude.
    assert 400 < soliton_speed_uncompressed(20.0, A_DIAM, E, NU, RHO) < 600


def test_precompressed_increases_with_amplitude_and_precompression():
    fr = np.linspace(1.0, 50.0, 200)
    v = soliton_speed_precompressed(fr * 1.0, 1.0, A_DIAM, E, NU, RHO)
    assert np.all(np.diff(v) > 0)
    # Same peak force, more precompression -> faster (paper §5.3, MsS bias).
    assert (soliton_speed_precompressed(20.0, 1.8, A_DIAM, E, NU, RHO)
            > soliton_speed_precompressed(20.0, 0.01, A_DIAM, E, NU, RHO))
