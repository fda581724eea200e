"""Alignment of sampled signals: threshold crossings, cross-correlation delays, sub-sample
shifts, aligning shots on a common time axis.

Conventions as :mod:`msens.signals.processing`: time runs along ``axis`` (default 0), times
in s, signals in any unit.
"""

from __future__ import annotations

import numpy as np
from scipy import fft, optimize

from msens.errors import InputError
from msens.signals.processing import _time_and_signal


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
    ``sqrt(2) noise / sqrt(sum(ds/dn ** 2))`` samples (tests/signals/test_processing.py).
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
