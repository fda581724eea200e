"""Processing of sampled signals: baseline, shot statistics, integration, filters.

Alignment (threshold crossings, delays, shifts) is :mod:`msens.signals.alignment`.

Pure functions on arrays. Unless said otherwise, time runs along ``axis`` (default 0, as
in :attr:`msens.io.Waveform.data` of shape (nt, nch)); other axes are carried along.
Times are in s, frequencies in Hz, signals in any unit (usually V).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import signal
from scipy.integrate import cumulative_trapezoid

from msens.errors import InputError


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
