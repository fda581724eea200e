"""Tests of the pulse features (msens.signals.features) on synthetic records with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.signals.features import (
    PulseFeatures,
    centre_distance,
    expected_round_trip,
    pulse_features,
    wave_speed,
)

FWHM_PER_SIGMA = 2 * np.sqrt(2 * np.log(2))


def gauss(t, t0, amp, sigma):
    return amp * np.exp(-0.5 * ((t - t0) / sigma) ** 2)


def record(t, t_inc=101.3e-6, f_inc=20.0, t_ref=419.7e-6, f_ref=11.0, sigma=9e-6):
    return gauss(t, t_inc, f_inc, sigma) + gauss(t, t_ref, f_ref, sigma)


T = np.arange(0.0, 600e-6, 0.1e-6)  # 10 MHz, the paper's sampling rate


def test_two_gaussians_tof_ar_width():
    pf = pulse_features(record(T), T)
    # Sub-sample accuracy of the parabolic vertex on a Gaussian sampled at sigma/90.
    assert pf.t_incident == pytest.approx(101.3e-6, abs=1e-9)
    assert pf.t_reflected == pytest.approx(419.7e-6, abs=1e-9)
    assert pf.f_incident == pytest.approx(20.0, rel=1e-5)
    assert pf.f_reflected == pytest.approx(11.0, rel=1e-5)
    assert pf.tof == pytest.approx(318.4e-6, abs=2e-9)
    assert pf.ar == pytest.approx(0.55, rel=1e-5)
    assert pf.width == pytest.approx(FWHM_PER_SIGMA * 9e-6, rel=1e-4)


def test_parabolic_interpolation_exact_for_parabola():
    t = np.arange(0.0, 1e-3, 1e-6)
    tp = 312.37e-6
    s = np.clip(1.0 - ((t - tp) / 40e-6) ** 2, 0.0, None)  # parabolic cap, off-grid vertex
    s = s + 0.5 * np.clip(1.0 - ((t - 800.21e-6) / 40e-6) ** 2, 0.0, None)
    pf = pulse_features(s, t)
    assert pf.t_incident == pytest.approx(tp, abs=1e-15)
    assert pf.f_incident == pytest.approx(1.0, rel=1e-12)
    assert pf.t_reflected == pytest.approx(800.21e-6, abs=1e-15)
    assert pf.ar == pytest.approx(0.5, rel=1e-12)


def test_coarse_sampling_subsample_accuracy():
    t = np.arange(0.0, 600e-6, 2e-6)  # sigma / dt = 4.5
    pf = pulse_features(record(t), t)
    # The vertex of the parabola is within 2% of dt and 1% in amplitude of the true peak.
    assert abs(pf.t_incident - 101.3e-6) < 0.02 * 2e-6
    assert abs(pf.tof - 318.4e-6) < 0.04 * 2e-6
    assert abs(pf.ar - 0.55) < 0.01


def test_secondary_pulse_on_the_tail_and_precursor_are_ignored():
    # Rod-like: a trailing secondary hump on the incident pulse's tail (bigger than the
    # reflection) and a negative precursor (MsS trough) before it.
    s = record(T) + gauss(T, 125e-6, 13.0, 6e-6) - gauss(T, 80e-6, 5.0, 5e-6)
    pf = pulse_features(s, T)
    assert pf.t_reflected == pytest.approx(419.7e-6, abs=1e-8)
    assert pf.ar == pytest.approx(0.55, rel=1e-3)


def test_min_delay_excludes_late_secondary_pulse():
    # A separate secondary pulse (decayed incident, then 14 N at 200 us) precedes the
    # reflection: only the round-trip guard can exclude it.
    s = record(T) + gauss(T, 200e-6, 14.0, 8e-6)
    assert pulse_features(s, T).t_reflected == pytest.approx(200e-6, abs=1e-8)
    rt = expected_round_trip(0.08, 500.0)  # 320 us
    assert rt == pytest.approx(320e-6)
    pf = pulse_features(s, T, min_delay=0.5 * rt)
    assert pf.t_reflected == pytest.approx(419.7e-6, abs=1e-8)


def test_ripple_on_rising_edge_does_not_split_incident():
    s = record(T) + 0.3 * np.sin(2 * np.pi * T / 3e-6) * (T < 95e-6) * (T > 85e-6)
    pf = pulse_features(s, T)
    assert pf.t_incident == pytest.approx(101.3e-6, abs=1e-9)


def test_batch_matches_loop_and_min_delay_broadcasts():
    rng = np.random.default_rng(42)
    n = 7
    ti = rng.uniform(80e-6, 120e-6, n)
    tr = rng.uniform(300e-6, 450e-6, n)
    fi = rng.uniform(10, 30, n)
    ar = rng.uniform(0.3, 0.9, n)
    s = np.stack([record(T, ti[k], fi[k], tr[k], ar[k] * fi[k]) for k in range(n)])
    s = s.reshape(7, 1, T.size)
    pf = pulse_features(s, T, min_delay=np.full((7, 1), 50e-6))
    assert pf.tof.shape == (7, 1)
    for k in range(n):
        one = pulse_features(s[k, 0], T, min_delay=50e-6)
        assert one.tof.shape == ()
        assert pf.tof[k, 0] == pytest.approx(one.tof, rel=1e-12)
        assert pf.ar[k, 0] == pytest.approx(one.ar, rel=1e-12)
    np.testing.assert_allclose(pf.tof[:, 0], tr - ti, atol=1e-9)
    np.testing.assert_allclose(pf.ar[:, 0], ar, rtol=1e-5)


def test_missing_reflection_and_empty_record_give_nan():
    s = np.stack([gauss(T, 500e-6, 1.0, 20e-6), np.zeros_like(T)])  # no decay / no pulse
    pf = pulse_features(s, T)
    assert np.isnan(pf.t_reflected).all()
    assert np.isnan(pf.ar).all()
    assert np.isnan(pf.f_incident[1])
    assert pf.t_incident[0] == pytest.approx(500e-6, abs=1e-9)


def test_speed_and_distance():
    # Beads of 4.76 mm with a 6 mm rod at 13: centres 13 -> 18 are 4 * 4.76 + 3 + 2.38 mm.
    length = np.full(30, 4.76e-3)
    length[12] = 6e-3
    d = centre_distance(length, 13, 18)
    assert d == pytest.approx(4 * 4.76e-3 + 3e-3 + 2.38e-3)
    assert centre_distance(np.full(30, 4.76e-3), 13, 18) == pytest.approx(5 * 4.76e-3)
    assert wave_speed(0.0238, 100e-6, 150e-6) == pytest.approx(476.0)
    with pytest.raises(InputError, match="p_first < p_second"):
        centre_distance(length, 18, 13)


def test_bad_inputs():
    with pytest.raises(InputError, match="uniformly spaced"):
        pulse_features(np.zeros(6), np.array([0, 1, 2, 3, 4, 6.0]))
    with pytest.raises(InputError, match="threshold"):
        pulse_features(record(T), T, threshold=0.0)
    with pytest.raises(InputError, match="matching the signal"):
        pulse_features(record(T), T[:-1])


def test_pulse_features_dataclass_is_frozen():
    pf = PulseFeatures(*(np.array(1.0),) * 5)
    with pytest.raises(AttributeError):
        pf.width = np.array(2.0)


def test_noisy_records_least_squares_peak():
    # 1 % white noise at 10 MHz on pulses of sigma = 9 us (FWHM 212 samples): the 3-point
    # parabola follows the noise; a least-squares parabola over +-40 samples averages it.
    rng = np.random.default_rng(7)
    s = record(T, f_inc=1.0, f_ref=0.5) + 1e-2 * rng.standard_normal((256, T.size))
    sharp = pulse_features(s, T)
    smooth = pulse_features(s, T, fit_half_width=40)
    assert not np.isnan(sharp.ar).any()
    assert abs(np.mean(smooth.ar) - 0.5) < 2e-3
    assert np.std(smooth.ar) < 0.5 * np.std(sharp.ar)
    assert np.std(smooth.tof) < 0.3e-6
    assert abs(np.mean(smooth.tof) - 318.4e-6) < 0.1e-6
