"""Processing of sampled signals: baseline, alignment, shot statistics, integration, filters.

Pure functions on arrays. Unless said otherwise, time runs along ``axis`` (default 0, as
in :attr:`msens.io.Waveform.data` of shape (nt, nch)); other axes are carried along.
Times are in s, frequencies in Hz, signals in any unit (usually V).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import fft, optimize, signal
from scipy.integrate import cumulative_trapezoid

from msens.errors import InputError

# ---------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------


def _time_and_signal(
    time: np.ndarray, values: np.ndarray, axis: int
) -> tuple[np.ndarray, np.ndarray, int]:
    time = np.asarray(time, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if time.ndim != 1:
        raise InputError(f"time must be 1-D, got shape {time.shape}")
    if values.ndim == 0:
        raise InputError("signal must have a time axis, got a scalar")
    axis = axis % values.ndim
    if values.shape[axis] != time.size:
        raise InputError(
            f"signal has {values.shape[axis]} samples along axis {axis}, time has {time.size}"
        )
    return time, values, axis


def _window_mask(time: np.ndarray, window: tuple[float, float], label: str) -> np.ndarray:
    start, end = window
    if not start < end:
        raise InputError(f"{label} window must have start < end, got ({start}, {end})")
    mask = (time >= start) & (time <= end)
    if not mask.any():
        raise InputError(
            f"{label} window ({start:g}, {end:g}) s holds no sample; the record spans "
            f"{time[0]:g} .. {time[-1]:g} s"
        )
    return mask


# ---------------------------------------------------------------------------------------
# Baseline
# ---------------------------------------------------------------------------------------


def baseline(
    time: np.ndarray,
    values: np.ndarray,
    window: tuple[float, float] | None = None,
    axis: int = 0,
) -> np.ndarray:
    """Mean of the signal over a pre-trigger window.

    Parameters
    ----------
    time : ndarray, shape (nt,)
        Sample times, s.
    values : ndarray, shape (..., nt, ...)
        Signal with time along ``axis``.
    window : (float, float), optional
        Closed time interval, s; default: all samples before the trigger (time < 0).
    axis : int
        Time axis of ``values``.

    Returns
    -------
    ndarray
        ``values``'s shape without ``axis``: the baseline of each trace.
    """
    time, values, axis = _time_and_signal(time, values, axis)
    if window is None:
        mask = time < 0.0
        if not mask.any():
            raise InputError("no pre-trigger samples (time < 0) for the baseline; give a window")
    else:
        mask = _window_mask(time, window, "baseline")
    return np.compress(mask, values, axis=axis).mean(axis=axis)


def remove_baseline(
    time: np.ndarray,
    values: np.ndarray,
    window: tuple[float, float] | None = None,
    axis: int = 0,
) -> np.ndarray:
    """Signal minus its :func:`baseline` (same shape as ``values``)."""
    time, values, axis = _time_and_signal(time, values, axis)
    return values - np.expand_dims(baseline(time, values, window, axis), axis)


# ---------------------------------------------------------------------------------------
# Alignment
# ---------------------------------------------------------------------------------------


def threshold_crossing(
    time: np.ndarray,
    values: np.ndarray,
    level: float,
    *,
    rising: bool = True,
    after: float | None = None,
    axis: int = 0,
) -> np.ndarray:
    """Time of the first crossing of ``level``, linearly interpolated between samples.

    Parameters
    ----------
    time : ndarray, shape (nt,)
        Sample times, s.
    values : ndarray
        Signals, time along ``axis``.
    level : float
        Threshold, in the signal's unit.
    rising : bool
        Look for an upward crossing (``s[i] < level <= s[i+1]``), else downward.
    after : float, optional
        Ignore crossings before this time, s.
    axis : int
        Time axis.

    Returns
    -------
    ndarray
        Crossing times, s, shape of ``values`` without ``axis``; NaN where the level is
        never crossed.

    Notes
    -----
    Linear interpolation errs by about ``dt**2 |s''| / (8 |s'|)``; for a Gaussian pulse of
    width sigma crossed at half height that is below ``0.05 dt * dt / sigma``.
    """
    time, values, axis = _time_and_signal(time, values, axis)
    s = np.moveaxis(values, axis, -1)
    sign = 1.0 if rising else -1.0
    below = sign * (s[..., :-1] - level) < 0.0
    above = sign * (s[..., 1:] - level) >= 0.0
    hit = below & above
    if after is not None:
        hit &= time[1:] >= after
    found = hit.any(axis=-1)
    i = np.argmax(hit, axis=-1)
    s0 = np.take_along_axis(s, i[..., None], axis=-1)[..., 0]
    s1 = np.take_along_axis(s, (i + 1)[..., None], axis=-1)[..., 0]
    frac = (level - s0) / np.where(found, s1 - s0, 1.0)
    crossing = time[i] + frac * (time[i + 1] - time[i])
    return np.where(found, crossing, np.nan)


def xcorr_delay(
    reference: np.ndarray,
    values: np.ndarray,
    dt: float,
    *,
    max_lag: float | None = None,
) -> float:
    """Delay of ``values`` relative to ``reference`` by cross-correlation, sub-sample.

    Parameters
    ----------
    reference, values : ndarray, shape (nt,)
        Two records on the same time grid.
    dt : float
        Sampling interval, s.
    max_lag : float, optional
        Largest delay searched, s (both signs); default the whole record.

    Returns
    -------
    float
        Delay, s: positive when ``values`` lags ``reference``.

    Notes
    -----
    The integer-lag peak of the (zero-padded, hence linear) correlation is refined by
    maximising its band-limited Fourier interpolation within one sample of that peak,
    which is exact for band-limited records; parabolic peak fits bias the estimate
    toward integer lags instead. Broadband noise enters through its own correlation
    over the whole record; low-pass both records first (e.g. :func:`lowpass` a few times
    above the pulse band), after which the error reaches the Cramér–Rao bound
    ``sqrt(2) noise / sqrt(sum(ds/dn ** 2))`` samples (tests/test_processing.py).
    """
    a = np.asarray(reference, dtype=np.float64)
    b = np.asarray(values, dtype=np.float64)
    if a.ndim != 1 or a.shape != b.shape:
        raise InputError(
            f"reference and signal must be 1-D of equal length, got {a.shape} and {b.shape}"
        )
    if a.size < 2 or not (dt > 0):
        raise InputError(f"need >= 2 samples and dt > 0, got {a.size} samples, dt = {dt}")
    nfft = fft.next_fast_len(2 * a.size)
    cross = fft.rfft(b, nfft) * np.conj(fft.rfft(a, nfft))
    corr = fft.irfft(cross, nfft)
    lags = np.arange(nfft)
    lags[lags >= nfft // 2] -= nfft
    limit = a.size - 1 if max_lag is None else min(a.size - 1, int(np.floor(max_lag / dt)))
    allowed = np.abs(lags) <= limit
    k = int(np.argmax(np.where(allowed, corr, -np.inf)))
    # One-sided weights turn the rfft half spectrum into the full real inverse sum.
    weight = np.full(cross.size, 2.0)
    weight[0] = 1.0
    if nfft % 2 == 0:
        weight[-1] = 1.0
    phase = 2j * np.pi * np.arange(cross.size) / nfft
    wc = weight * cross

    def negative_corr(lag: float) -> float:
        return -float(np.real(np.sum(wc * np.exp(phase * lag)))) / nfft

    lag0 = float(lags[k])
    best = optimize.minimize_scalar(
        negative_corr,
        bounds=(lag0 - 1.0, lag0 + 1.0),
        method="bounded",
        options={"xatol": 1e-7},
    )
    return float(best.x) * dt


def shift_signal(values: np.ndarray, delay: float, dt: float, axis: int = 0) -> np.ndarray:
    """Signal delayed by ``delay`` seconds (any fraction of a sample), same shape.

    Uses a Fourier phase ramp on a zero-padded copy, exact for band-limited signals that
    start and end near zero; samples shifted in from outside the record are ~0.

    Parameters
    ----------
    values : ndarray
        Signal, time along ``axis``.
    delay : float
        Delay, s; positive moves features later.
    dt : float
        Sampling interval, s.
    axis : int
        Time axis.
    """
    values = np.asarray(values, dtype=np.float64)
    if not (dt > 0):
        raise InputError(f"dt must be positive, got {dt}")
    n = values.shape[axis]
    nfft = fft.next_fast_len(2 * n)
    spectrum = fft.rfft(values, nfft, axis=axis)
    freq = fft.rfftfreq(nfft, dt)
    ramp = np.exp(-2j * np.pi * freq * delay)
    shape = [1] * values.ndim
    shape[axis] = freq.size
    shifted = fft.irfft(spectrum * ramp.reshape(shape), nfft, axis=axis)
    return np.take(shifted, np.arange(n), axis=axis)


def align_shots(shots: np.ndarray, delays: np.ndarray, dt: float) -> np.ndarray:
    """Shift each shot back by its delay so all shots line up.

    Parameters
    ----------
    shots : ndarray, shape (nshots, nt, ...)
        Records, time along axis 1.
    delays : ndarray, shape (nshots,)
        Delay of each shot, s (e.g. from :func:`threshold_crossing` minus a reference).
    dt : float
        Sampling interval, s.

    Returns
    -------
    ndarray, shape (nshots, nt, ...)
    """
    shots = np.asarray(shots, dtype=np.float64)
    delays = np.asarray(delays, dtype=np.float64)
    if shots.ndim < 2 or delays.shape != (shots.shape[0],):
        raise InputError(
            f"shots must be (nshots, nt, ...) with one delay per shot, got shots "
            f"{shots.shape} and delays {delays.shape}"
        )
    if not np.all(np.isfinite(delays)):
        raise InputError("delays must be finite (a NaN delay means no trigger was found)")
    return np.stack([shift_signal(s, -d, dt, axis=0) for s, d in zip(shots, delays, strict=True)])


# ---------------------------------------------------------------------------------------
# Shot statistics
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ShotStatistics:
    """Statistics over repeated shots.

    Attributes
    ----------
    n_shots : int
        Number of shots.
    mean : ndarray, shape (nt, ...)
        Sample mean over shots.
    std : ndarray, shape (nt, ...)
        Sample standard deviation over shots (ddof = 1).
    sem : ndarray, shape (nt, ...)
        Standard error of the mean, ``std / sqrt(n_shots)``.
    features : ndarray or None, shape (nshots, ...)
        Per-shot features from the feature function, if one was given.
    feature_mean, feature_std : ndarray or None, shape (...)
        Mean and sample standard deviation (ddof = 1) of the features.
    """

    n_shots: int
    mean: np.ndarray
    std: np.ndarray
    sem: np.ndarray
    features: np.ndarray | None = None
    feature_mean: np.ndarray | None = None
    feature_std: np.ndarray | None = None


def shot_statistics(
    shots: np.ndarray, feature: Callable[[np.ndarray], object] | None = None
) -> ShotStatistics:
    """Mean, spread and per-shot features of repeated records.

    Parameters
    ----------
    shots : ndarray, shape (nshots, nt, ...)
        Aligned records, shots along axis 0; nshots >= 2.
    feature : callable, optional
        Maps one shot (shape (nt, ...)) to a number or array (e.g. peak amplitude).

    Returns
    -------
    ShotStatistics
    """
    shots = np.asarray(shots, dtype=np.float64)
    if shots.ndim < 2 or shots.shape[0] < 2:
        raise InputError(
            f"shots must be (nshots, nt, ...) with nshots >= 2 for a spread, got {shots.shape}"
        )
    n = shots.shape[0]
    std = shots.std(axis=0, ddof=1)
    features = feature_mean = feature_std = None
    if feature is not None:
        features = np.asarray([feature(s) for s in shots], dtype=np.float64)
        feature_mean = features.mean(axis=0)
        feature_std = features.std(axis=0, ddof=1)
    return ShotStatistics(
        n_shots=n,
        mean=shots.mean(axis=0),
        std=std,
        sem=std / np.sqrt(n),
        features=features,
        feature_mean=feature_mean,
        feature_std=feature_std,
    )


# ---------------------------------------------------------------------------------------
# Integration of MsS voltage
# ---------------------------------------------------------------------------------------


def integrate_drift_corrected(
    time: np.ndarray,
    voltage: np.ndarray,
    pulse_window: tuple[float, float],
    *,
    order: int = 1,
    axis: int = 0,
) -> np.ndarray:
    """Running integral of a voltage with the drift outside the pulse removed.

    The MsS voltage is proportional to dF/dt, so its integral follows the force and must
    return to its starting value once the pulse has passed. A small offset in the voltage
    (amplifier, DAQ) integrates to a ramp. The cumulative trapezoidal integral is taken,
    a polynomial of degree ``order`` in time is fitted by least squares to it at the
    samples outside ``pulse_window``, and subtracted: the result is ~0 before and after
    the pulse. ``order=1`` removes a constant voltage offset exactly, ``order=2`` also a
    linear voltage drift.

    Parameters
    ----------
    time : ndarray, shape (nt,)
        Sample times, s.
    voltage : ndarray
        Voltage, V, time along ``axis``.
    pulse_window : (float, float)
        Time interval holding the pulse(s), s; samples outside define the baseline.
    order : int
        Polynomial degree of the baseline, 0..3.
    axis : int
        Time axis.

    Returns
    -------
    ndarray
        Integral, V s, same shape as ``voltage``.

    Notes
    -----
    Trapezoidal integration errs by O(dt^2): for the derivative of a Gaussian of width
    sigma, by about ``(dt/sigma)**2 / 12`` of the peak.
    """
    time, voltage, axis = _time_and_signal(time, voltage, axis)
    if order not in (0, 1, 2, 3):
        raise InputError(f"order must be 0, 1, 2 or 3, got {order!r}")
    start, end = pulse_window
    if not start < end:
        raise InputError(f"pulse window must have start < end, got ({start}, {end})")
    outside = (time < start) | (time > end)
    if outside.sum() < order + 2:
        raise InputError(
            f"pulse window ({start:g}, {end:g}) s leaves {int(outside.sum())} samples "
            f"outside it; a degree-{order} baseline needs at least {order + 2}"
        )
    integral = cumulative_trapezoid(voltage, time, axis=axis, initial=0.0)
    moved = np.moveaxis(integral, axis, 0)
    flat = moved.reshape(time.size, -1)
    # Scaled time keeps the Vandermonde matrix well conditioned for microsecond records.
    centre, half = 0.5 * (time[0] + time[-1]), 0.5 * (time[-1] - time[0])
    x = (time - centre) / half
    coef = np.polynomial.polynomial.polyfit(x[outside], flat[outside], order)
    fitted = np.polynomial.polynomial.polyval(x, coef).T.reshape(moved.shape)
    return np.moveaxis(moved - fitted, 0, axis)


# ---------------------------------------------------------------------------------------
# Zero-phase Butterworth filters
# ---------------------------------------------------------------------------------------


def _zero_phase(
    values: np.ndarray,
    dt: float,
    btype: str,
    cutoff: float | tuple[float, float],
    order: int,
    axis: int,
) -> np.ndarray:
    values = np.asarray(values, dtype=np.float64)
    if not (dt > 0):
        raise InputError(f"dt must be positive, got {dt}")
    if isinstance(order, bool) or not isinstance(order, int) or not 1 <= order <= 12:
        raise InputError(f"filter order must be an integer 1..12, got {order!r}")
    nyquist = 0.5 / dt
    edges = np.atleast_1d(np.asarray(cutoff, dtype=np.float64))
    if not np.all((edges > 0) & (edges < nyquist)) or np.any(np.diff(edges) <= 0):
        raise InputError(
            f"{btype} cutoff {cutoff} Hz must be increasing and inside (0, {nyquist:g}) Hz "
            "(the Nyquist frequency)"
        )
    expected = 2 if btype == "bandpass" else 1
    if edges.size != expected:
        raise InputError(f"{btype} needs {expected} cutoff frequencies, got {cutoff}")
    wn = edges if expected == 2 else float(edges[0])
    sos = signal.butter(order, wn, btype=btype, fs=1.0 / dt, output="sos")
    try:
        return signal.sosfiltfilt(sos, values, axis=axis)
    except ValueError as exc:
        raise InputError(f"{btype} filter: signal too short ({exc})") from None


def lowpass(
    values: np.ndarray, dt: float, cutoff: float, order: int = 4, axis: int = 0
) -> np.ndarray:
    """Zero-phase Butterworth low-pass (forward-backward, ``scipy.signal.sosfiltfilt``).

    Parameters
    ----------
    values : ndarray
        Signal, time along ``axis``.
    dt : float
        Sampling interval, s.
    cutoff : float
        -3 dB frequency of the single pass, Hz; the forward-backward pair squares the
        response, so a sine at ``cutoff`` keeps half its amplitude (-6 dB).
    order : int
        Butterworth order of one pass (the pair has twice the roll-off).
    axis : int
        Time axis.
    """
    return _zero_phase(values, dt, "lowpass", cutoff, order, axis)


def highpass(
    values: np.ndarray, dt: float, cutoff: float, order: int = 4, axis: int = 0
) -> np.ndarray:
    """Zero-phase Butterworth high-pass; arguments as :func:`lowpass`."""
    return _zero_phase(values, dt, "highpass", cutoff, order, axis)


def bandpass(
    values: np.ndarray, dt: float, band: tuple[float, float], order: int = 4, axis: int = 0
) -> np.ndarray:
    """Zero-phase Butterworth band-pass between ``band = (low, high)`` Hz; see :func:`lowpass`."""
    return _zero_phase(values, dt, "bandpass", band, order, axis)
