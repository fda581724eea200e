"""Tests of the calibrations (msens.calibrate)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from msens.calibrate import (
    dissipation_objective,
    fit_dissipation,
    precompression_from_speed,
    voltage_to_force_factor,
)
from msens.errors import InputError
from msens.mechanics.longwave import soliton_speed_precompressed, soliton_speed_uncompressed

A_DIAM, E, NU, RHO = 4.76e-3, 200e9, 0.29, 7970.0
N = 30
T = np.arange(0.0, 600e-6, 0.5e-6)


def _gauss(t, t0, sigma=9e-6):
    return np.exp(-0.5 * ((t - t0) / sigma) ** 2)


def fake_chain(gamma_c, gamma_w):
    return SimpleNamespace(gamma_c=gamma_c, gamma_w=gamma_w, n_particles=N)


def fake_simulator(chains, velocities, t_out, contacts):
    """Stand-in for simulate_batch(..., contacts=...) with known AR(gamma): reflected
    amplitudes at the top (13) and bottom (18) sensors decay exponentially with the chains'
    gamma_c, gamma_w."""
    runs = len(chains)
    force = np.full((runs, t_out.size, N), 0.05)  # static force, removed by the sensors
    for r, c in enumerate(chains):
        for p, t_inc, t_ref, kc in ((13, 110e-6, 430e-6, 0.10), (18, 155e-6, 385e-6, 0.06)):
            ar = np.exp(-kc * c.gamma_c - 0.05 * c.gamma_w)
            pulse = 8.0 * (_gauss(t_out, t_inc) + ar * _gauss(t_out, t_ref))
            force[r, :, p - 2:p] += pulse[:, None]
    return SimpleNamespace(force=force[..., contacts], t=t_out)


def _target(gc, gw):
    return np.exp(-0.10 * gc - 0.05 * gw), np.exp(-0.06 * gc - 0.05 * gw)


def test_objective_is_paper_eq10():
    y = dissipation_objective([0.6, np.nan], [0.7, 0.7], 0.5, 0.8)
    assert y[0] == pytest.approx(np.hypot(0.1 / 0.5, 0.1 / 0.8))
    assert y[1] == np.inf


def test_fit_recovers_interior_optimum():
    ar_t, ar_b = _target(3.3, 1.7)
    fit = fit_dissipation(fake_chain, (13, 18), ar_t, ar_b, 0.3758, T,
                          simulator=fake_simulator, xatol=1e-5, fatol=1e-10)
    assert fit.gamma_c == pytest.approx(3.3, abs=2e-3)
    assert fit.gamma_w == pytest.approx(1.7, abs=4e-3)
    assert fit.objective < 1e-4
    assert fit.ar_top_model == pytest.approx(ar_t, rel=1e-4)
    assert fit.tof_top_model == pytest.approx(320e-6, abs=1e-8)
    assert fit.tof_bottom_model == pytest.approx(230e-6, abs=1e-8)
    assert fit.n_simulations > 91


def test_fit_stops_at_the_gamma_w_bound():
    # Targets that would need gamma_w < 0: the constrained optimum is on gamma_w = 0, and
    # there the best gamma_c minimises Eq. 10 along the bound (checked by a dense 1-D scan).
    ar_t, ar_b = _target(4.0, -1.0)
    fit = fit_dissipation(fake_chain, (13, 18), ar_t, ar_b, 0.3758, T,
                          simulator=fake_simulator, xatol=1e-5, fatol=1e-12)
    assert fit.gamma_w == pytest.approx(0.0, abs=1e-3)
    gcs = np.linspace(0, 10, 20001)
    a, b = _target(gcs, 0.0)
    y = dissipation_objective(a, b, ar_t, ar_b)
    assert fit.gamma_c == pytest.approx(gcs[np.argmin(y)], abs=2e-3)
    assert fit.objective == pytest.approx(y.min(), rel=1e-4)


def test_fit_rejects_bad_input():
    with pytest.raises(InputError, match="amplitude ratios"):
        fit_dissipation(fake_chain, (13, 18), 0.0, 0.7, 0.3, T,
                        simulator=fake_simulator)
    with pytest.raises(InputError, match="no grid point"):
        fit_dissipation(fake_chain, (13, 18), 0.5, 0.7, 0.3, T,
                        simulator=fake_simulator, min_delay=(1e-3, 1e-3), refine=False)


def test_voltage_to_force_factor():
    rng = np.random.default_rng(0)
    v = rng.normal(0.2, 0.004, 500)  # 500 shots (paper §2), V
    mean, std = voltage_to_force_factor(6.0, v)
    k = 6.0 / v
    assert mean == pytest.approx(k.mean(), rel=1e-14)
    assert std == pytest.approx(k.std(ddof=1), rel=1e-14)
    assert voltage_to_force_factor(6.0, [0.2]) == (pytest.approx(30.0), 0.0)
    # Per-shot model peaks broadcast against the shots.
    assert voltage_to_force_factor([6.0, 3.0], [0.2, 0.1])[0] == pytest.approx(30.0)
    with pytest.raises(InputError, match="non-zero"):
        voltage_to_force_factor(6.0, [0.2, 0.0])


@pytest.mark.parametrize("F0", [1e-3, 0.05, 1.8, 40.0])
@pytest.mark.parametrize("amplitude", ["dynamic", "total"])
def test_precompression_inverts_forward_formula(F0, amplitude):
    F_dyn = 8.0
    total = F0 + F_dyn
    speed = soliton_speed_precompressed(total, F0, A_DIAM, E, NU, RHO)
    F_m = F_dyn if amplitude == "dynamic" else total
    got = precompression_from_speed(speed, F_m, A_DIAM, E, NU, RHO, amplitude=amplitude)
    assert got == pytest.approx(F0, rel=1e-8)


def test_precompression_out_of_range_speeds():
    v_un = soliton_speed_uncompressed(8.0, A_DIAM, E, NU, RHO)
    with pytest.raises(InputError, match="uncompressed"):
        precompression_from_speed(0.99 * v_un, 8.0, A_DIAM, E, NU, RHO)
    with pytest.raises(InputError, match="sound speed"):
        precompression_from_speed(2 * v_un, 8.0, A_DIAM, E, NU, RHO, amplitude="total")
