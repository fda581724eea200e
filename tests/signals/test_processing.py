"""Processing functions against analytic signals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from msens.errors import InputError
from msens.signals import alignment as A
from msens.signals import processing as P

DT = 1e-7  # 10 MHz, the paper's sampling rate
TIME = -2e-5 + DT * np.arange(2000)
SIGMA = 30 * DT  # pulse width: 3 us, 30 samples


def gaussian(t0: float, time: np.ndarray = TIME) -> np.ndarray:
    return np.exp(-0.5 * ((time - t0) / SIGMA) ** 2)


def hann_pulse(time: np.ndarray, start: float, width: float) -> np.ndarray:
    """sin^2 pulse, exactly zero outside [start, start + width]."""
    phase = np.clip((time - start) / width, 0.0, 1.0)
    return np.sin(np.pi * phase) ** 2


# --- baseline -------------------------------------------------------------------------


def test_baseline_removal_is_exact_on_constant_plus_pulse() -> None:
    """Exact up to the rounding of a 1000-sample mean (~1e-14 for offsets of order 1)."""
    pulse = hann_pulse(TIME, 5e-6, 2e-5)
    offsets = np.array([0.3, -1.7, 1e-3])
    signals = pulse[:, None] * [1.0, 2.0, -0.5] + offsets
    cleaned = P.remove_baseline(TIME, signals)
    np.testing.assert_allclose(cleaned, pulse[:, None] * [1.0, 2.0, -0.5], rtol=0, atol=1e-14)
    np.testing.assert_allclose(P.baseline(TIME, signals), offsets, rtol=1e-14)
    # time on the last axis, explicit window
    np.testing.assert_allclose(
        P.remove_baseline(TIME, signals.T, window=(-2e-5, -1e-5), axis=1),
        cleaned.T,
        rtol=0,
        atol=1e-14,
    )


def test_baseline_needs_samples() -> None:
    with pytest.raises(InputError, match="no pre-trigger samples"):
        P.baseline(TIME + 1.0, np.zeros(TIME.size))
    with pytest.raises(InputError, match=r"holds no sample; the record spans"):
        P.baseline(TIME, np.zeros(TIME.size), window=(1.0, 2.0))
    with pytest.raises(InputError, match="start < end"):
        P.baseline(TIME, np.zeros(TIME.size), window=(0.0, -1.0))
    with pytest.raises(InputError, match="samples along axis 0"):
        P.baseline(TIME, np.zeros(TIME.size + 1))


# --- alignment ------------------------------------------------------------------------

FRACTIONS = [0.0, 0.13, 0.37, 0.5, 0.81, -0.29]


@pytest.mark.parametrize("fraction", FRACTIONS)
def test_xcorr_recovers_fractional_shift(fraction: float) -> None:
    delay = (25 + fraction) * DT
    estimate = A.xcorr_delay(gaussian(5e-5), gaussian(5e-5 + delay), DT)
    # Requirement: 1 % of dt. The band-limited refinement gives ~1e-6 dt.
    assert abs(estimate - delay) < 1e-4 * DT


def test_xcorr_with_noise_reaches_the_cramer_rao_bound() -> None:
    """Low-passed noisy pulses: delay error std ~ CRLB sqrt(2) noise / sqrt(sum(g'^2))."""
    delay, noise = -12.4 * DT, 0.01
    errors = []
    for seed in range(40):
        rng = np.random.default_rng(seed)
        ref, sig = (
            P.lowpass(gaussian(5e-5 + d) + rng.normal(scale=noise, size=TIME.size), DT, 2e5)
            for d in (0.0, delay)
        )
        errors.append((A.xcorr_delay(ref, sig, DT) - delay) / DT)
    slope = np.gradient(gaussian(5e-5))  # per sample
    crlb = np.sqrt(2.0) * noise / np.sqrt(np.sum(slope**2))  # 0.082 samples
    assert abs(np.mean(errors)) < 3 * crlb / np.sqrt(len(errors)) + 0.01
    assert 0.7 * crlb < np.std(errors) < 1.3 * crlb


def test_xcorr_lag_limit_ignores_a_decoy() -> None:
    delay = -12.4 * DT
    decoy = gaussian(5e-5 + delay) + 3.0 * gaussian(5e-5 + 600 * DT)
    assert abs(A.xcorr_delay(gaussian(5e-5), decoy, DT) - 600 * DT) < 0.01 * DT
    assert abs(A.xcorr_delay(gaussian(5e-5), decoy, DT, max_lag=50 * DT) - delay) < 0.01 * DT


@pytest.mark.parametrize("fraction", FRACTIONS)
def test_threshold_crossing_recovers_fractional_shift(fraction: float) -> None:
    delay = (25 + fraction) * DT
    both = np.column_stack([gaussian(5e-5), gaussian(5e-5 + delay)])
    t_rise = A.threshold_crossing(TIME, both, 0.5)
    t_fall = A.threshold_crossing(TIME, both, 0.5, rising=False, after=5e-5)
    # Interpolation error bound 0.05 dt^2/sigma per crossing = 0.0017 dt here.
    assert abs((t_rise[1] - t_rise[0]) - delay) < 0.01 * DT
    assert abs((t_fall[1] - t_fall[0]) - delay) < 0.01 * DT
    half_width = SIGMA * np.sqrt(2 * np.log(2))
    assert abs(t_rise[0] - (5e-5 - half_width)) < 0.01 * DT


def test_threshold_crossing_exact_on_a_ramp_and_nan_when_absent() -> None:
    ramp = 3.0 * TIME
    assert A.threshold_crossing(TIME, ramp, 3.0 * 1.234567e-5) == pytest.approx(
        1.234567e-5, rel=1e-12
    )
    assert np.isnan(A.threshold_crossing(TIME, gaussian(5e-5), 2.0))


@pytest.mark.parametrize("fraction", [0.13, 0.5, 0.81])
def test_shift_and_align_recover_the_pulse(fraction: float) -> None:
    delays = np.array([0.0, (3 + fraction) * DT, -(7 + fraction) * DT])
    shots = np.stack([gaussian(5e-5 + d) for d in delays])
    shifted = A.shift_signal(gaussian(5e-5), delays[1], DT)
    np.testing.assert_allclose(shifted, shots[1], rtol=0, atol=1e-12)
    aligned = A.align_shots(shots, delays, DT)
    np.testing.assert_allclose(aligned, np.broadcast_to(gaussian(5e-5), shots.shape), atol=1e-12)
    with pytest.raises(InputError, match="NaN delay"):
        A.align_shots(shots, np.array([0.0, np.nan, 0.0]), DT)


def test_threshold_align_average_pipeline() -> None:
    """Jittered shots: trigger by threshold, align, average: the mean is the template."""
    rng = np.random.default_rng(4)
    jitter = rng.uniform(-5, 5, size=50) * DT
    shots = np.stack([gaussian(5e-5 + j) for j in jitter])
    crossings = A.threshold_crossing(TIME, shots, 0.5, axis=1)
    aligned = A.align_shots(shots, crossings - crossings[0], DT)
    stats = P.shot_statistics(aligned)
    template = A.shift_signal(gaussian(5e-5), jitter[0], DT)
    assert np.max(np.abs(stats.mean - template)) < 1e-3
    assert np.max(stats.std) < 1e-3


# --- shot statistics ------------------------------------------------------------------


def test_shot_statistics_exact_for_scaled_shots() -> None:
    template = gaussian(5e-5)
    gains = np.array([0.9, 1.0, 1.1, 1.3])
    shots = gains[:, None] * template
    stats = P.shot_statistics(shots, feature=lambda s: [s.max(), s.argmax()])
    assert stats.n_shots == 4
    np.testing.assert_allclose(stats.mean, gains.mean() * template, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(stats.std, gains.std(ddof=1) * template, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(stats.sem, stats.std / 2.0)
    np.testing.assert_allclose(stats.features[:, 0], gains, rtol=1e-15)
    np.testing.assert_allclose(stats.feature_mean, [gains.mean(), 700.0], rtol=1e-15)
    np.testing.assert_allclose(stats.feature_std, [gains.std(ddof=1), 0.0], atol=1e-15)


def test_shot_statistics_of_noise_match_the_noise() -> None:
    rng = np.random.default_rng(9)
    n, noise = 500, 0.02  # the paper averaged 500 shots
    shots = gaussian(5e-5) + rng.normal(scale=noise, size=(n, TIME.size))
    stats = P.shot_statistics(shots)
    # The mean's error is N(0, noise/sqrt(n)) per sample: 5 sigma over 2000 samples.
    assert np.max(np.abs(stats.mean - gaussian(5e-5))) < 5 * noise / np.sqrt(n)
    # The sample std of n normals has relative spread 1/sqrt(2(n-1)) = 3.2 %.
    assert abs(np.mean(stats.std) / noise - 1.0) < 0.01
    with pytest.raises(InputError, match="nshots >= 2"):
        P.shot_statistics(shots[:1])


# --- integration ----------------------------------------------------------------------


def dgaussian(time: np.ndarray, t0: float) -> np.ndarray:
    return -(time - t0) / SIGMA**2 * gaussian(t0, time)


def test_integration_returns_gaussian_with_offset_removed() -> None:
    offset = 0.02 / SIGMA  # 2 % of the peak derivative scale: a large ramp if left in
    voltage = dgaussian(TIME, 5e-5) + offset
    window = (5e-5 - 8 * SIGMA, 5e-5 + 8 * SIGMA)
    result = P.integrate_drift_corrected(TIME, voltage, window, order=1)
    error = np.max(np.abs(result - gaussian(5e-5)))
    # Trapezoid error (dt/sigma)^2/12 = 9.3e-5 of the peak; allow 1.5x.
    assert error < 1.5 * (DT / SIGMA) ** 2 / 12
    raw = np.cumsum(voltage) * DT
    assert np.max(np.abs(raw - gaussian(5e-5))) > 100 * error  # the correction matters


def test_integration_order_two_removes_linear_voltage_drift_batched() -> None:
    drift = (0.01 + 2e3 * TIME) / SIGMA
    voltage = np.stack([dgaussian(TIME, 5e-5) + drift, 2.0 * dgaussian(TIME, 6e-5) - drift])
    window = (3e-5, 8e-5)
    result = P.integrate_drift_corrected(TIME, voltage, window, order=2, axis=1)
    expected = np.stack([gaussian(5e-5), 2.0 * gaussian(6e-5)])
    assert np.max(np.abs(result - expected)) < 1.5 * 2.0 * (DT / SIGMA) ** 2 / 12


def test_integration_converges_at_second_order() -> None:
    errors = []
    for dt in (4 * DT, 2 * DT, DT):
        time = np.arange(-2e-5, 1.8e-4, dt)
        result = P.integrate_drift_corrected(time, dgaussian(time, 5e-5) + 100.0, (3e-5, 7e-5))
        errors.append(np.max(np.abs(result - gaussian(5e-5, time))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    np.testing.assert_allclose(orders, 2.0, atol=0.05)


def test_integration_rejects_bad_windows() -> None:
    with pytest.raises(InputError, match="leaves 0 samples outside"):
        P.integrate_drift_corrected(TIME, np.zeros(TIME.size), (-1.0, 1.0))
    with pytest.raises(InputError, match="order must be"):
        P.integrate_drift_corrected(TIME, np.zeros(TIME.size), (0.0, 1e-5), order=5)


# --- filters --------------------------------------------------------------------------


def steady_amplitude(values: np.ndarray, freq: float) -> float:
    """Least-squares sine amplitude over the middle half (away from the ends)."""
    n = values.size
    mid = slice(n // 4, 3 * n // 4)
    t = TIME_LONG[mid]
    basis = np.column_stack([np.sin(2 * np.pi * freq * t), np.cos(2 * np.pi * freq * t)])
    coef, *_ = np.linalg.lstsq(basis, values[mid], rcond=None)
    return float(np.hypot(*coef))


TIME_LONG = DT * np.arange(40000)


def warped(freq: float) -> float:
    """Analog prototype frequency of a bilinear-transform digital filter (scipy's butter)."""
    return float(np.tan(np.pi * freq * DT))


def lp_gain(freq: float, cutoff: float, order: int = 4) -> float:
    """|H|^2 of a Butterworth low-pass: the forward-backward pair's amplitude gain."""
    return 1.0 / (1.0 + (warped(freq) / warped(cutoff)) ** (2 * order))


def bp_gain(freq: float, low: float, high: float, order: int = 4) -> float:
    w, w1, w2 = warped(freq), warped(low), warped(high)
    return 1.0 / (1.0 + ((w**2 - w1 * w2) / (w * (w2 - w1))) ** (2 * order))


@pytest.mark.parametrize(
    ("filt", "cutoff", "freq", "expected"),
    [
        (P.lowpass, 2e5, 2e5, 0.5),  # -6 dB at cutoff: forward-backward squares |H|
        (P.lowpass, 2e5, 2e4, lp_gain(2e4, 2e5)),  # passband: 1 - 1e-8
        (P.lowpass, 2e5, 8e5, lp_gain(8e5, 2e5)),  # stopband: 1.3e-5
        (P.highpass, 2e5, 2e5, 0.5),
        (P.highpass, 2e5, 8e5, 1.0 - lp_gain(8e5, 2e5)),  # |H_hp|^2 = 1 - |H_lp|^2
        (P.highpass, 2e5, 5e4, 1.0 - lp_gain(5e4, 2e5)),
        (P.bandpass, (1e5, 4e5), 2e5, bp_gain(2e5, 1e5, 4e5)),
        (P.bandpass, (1e5, 4e5), 1e6, bp_gain(1e6, 1e5, 4e5)),
    ],
)
def test_butterworth_magnitude(filt, cutoff, freq: float, expected: float) -> None:
    x = np.sin(2 * np.pi * freq * TIME_LONG)
    amplitude = steady_amplitude(filt(x, DT, cutoff), freq)
    assert amplitude == pytest.approx(expected, rel=1e-4, abs=1e-8)


def test_filters_are_zero_phase() -> None:
    t0 = 0.5 * (TIME[0] + TIME[-1]) + 0.3 * DT  # centred: edge transients stay symmetric
    pulse = gaussian(t0)

    def centroid(values: np.ndarray) -> float:
        weight = values**2
        return float(np.sum(weight * TIME) / np.sum(weight))

    for filtered in (P.lowpass(pulse, DT, 1e5), P.highpass(pulse, DT, 5e4)):
        assert abs(centroid(filtered) - t0) < 1e-3 * DT
    # a causal filter of the same design delays the pulse by many samples
    sos = signal.butter(4, 1e5, fs=1 / DT, output="sos")
    assert centroid(signal.sosfilt(sos, pulse)) - t0 > 10 * DT


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: P.lowpass(np.zeros(100), DT, 5e6), r"inside \(0, 5e\+06\) Hz"),
        (lambda: P.lowpass(np.zeros(100), DT, -1.0), "cutoff"),
        (lambda: P.bandpass(np.zeros(100), DT, (4e5, 1e5)), "increasing"),
        (lambda: P.lowpass(np.zeros(100), DT, 1e5, order=0), "order"),
        (lambda: P.lowpass(np.zeros(10), DT, 1e5), "too short"),
        (lambda: P.lowpass(np.zeros(100), 0.0, 1e5), "dt must be positive"),
    ],
)
def test_filter_input_errors(call, message: str) -> None:
    with pytest.raises(InputError, match=message):
        call()
