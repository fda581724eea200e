"""Features of solitary-pulse records: incident and reflected peaks, TOF, AR, speed, width.

Pure functions on sampled signals ``s`` of shape (..., nt) with uniform sample times ``t``
(nt,); every result has the batch shape (...). The paper's definitions (§5): TOF = time
between the incident and the reflected peak at one sensor, AR = reflected / incident peak
amplitude, speed = distance between two sensors / difference of their peak times.

Peak-picking rule (robust to the secondary pulses a piezo rod makes, paper §4.2):

1. incident pulse = the first excursion of ``s`` above ``threshold`` x its global maximum
   (it ends when ``s`` falls below half that level: hysteresis against noise); its peak is
   the largest sample of that excursion (so ripples on the rising edge and small
   precursors, like the MsS trough, are skipped);
2. width = full width at half of the incident peak (linear interpolation of the crossings);
3. the reflected search window opens at the latest of
   - t_incident + ``min_delay`` (e.g. a fraction of the expected wall round trip),
   - t_incident + ``guard_widths`` x width (the incident pulse has passed),
   - the first time after the incident peak where ``s`` falls below ``decay`` x the
     incident peak (the incident pulse has decayed, so trailing secondary humps riding on
     its tail are not taken for the reflection);
4. reflected pulse = the largest strict local maximum inside that window;
5. both peak times and amplitudes are refined by a parabola through the peak sample and its
   two neighbours (sub-sample accuracy; exact for a parabolic peak), or, for noisy records,
   a least-squares parabola through ``2 fit_half_width + 1`` samples.

A feature that cannot be found (no decay, no local maximum in the window, non-positive
signal) is NaN for that record.

The model's features (:func:`model_features`) are read by this one pipeline in every
workflow (``msens run``, ``compare``, ``diagnose``): a sensor's feature record (its force, or
for a physics MsS its integrated DAQ voltage, :func:`integrated`) and, where a workflow
reads the model as it reads measured records, the zero-phase low-pass of
:data:`FEATURE_CUTOFF_HZ` (:func:`smooth`) before the peaks are picked.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import cumulative_trapezoid

from msens.errors import require
from msens.signals.processing import lowpass


@dataclass(frozen=True)
class PulseFeatures:
    """Incident and reflected peaks of one record or a batch (arrays of the batch shape).

    Attributes
    ----------
    t_incident : ndarray
        Time of the incident peak, s.
    f_incident : ndarray
        Incident peak amplitude, signal units (N for forces, V for voltages).
    t_reflected : ndarray
        Time of the reflected peak, s (NaN if not found).
    f_reflected : ndarray
        Reflected peak amplitude, signal units (NaN if not found).
    width : ndarray
        Full width at half maximum of the incident pulse, s.
    """

    t_incident: np.ndarray
    f_incident: np.ndarray
    t_reflected: np.ndarray
    f_reflected: np.ndarray
    width: np.ndarray

    @property
    def tof(self) -> np.ndarray:
        """Time of flight t_reflected - t_incident, s."""
        return self.t_reflected - self.t_incident

    @property
    def ar(self) -> np.ndarray:
        """Amplitude ratio f_reflected / f_incident, dimensionless."""
        return self.f_reflected / self.f_incident


def _check_time(t: np.ndarray, nt: int) -> float:
    require(t.ndim == 1 and t.size == nt and nt >= 5,
            f"sample times t must have shape ({nt},) matching the signal (nt >= 5), got {t.shape}")
    dt = np.diff(t)
    step = float(t[-1] - t[0]) / (nt - 1)
    require(step > 0 and bool(np.all(np.abs(dt - step) <= 1e-6 * step)),
            "sample times t must be uniformly spaced and increasing")
    return step


def _parabolic(s: np.ndarray, i: np.ndarray, t0: float, dt: float,
               k: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Vertex of the least-squares parabola through samples i-k..i+k of each row of s (B, nt).

    For k = 1 the parabola passes through the three samples (classic interpolation, exact for
    a parabolic peak); larger k averages out noise. The vertex is kept within +-k samples.
    """
    nt = s.shape[-1]
    k = int(min(k, (nt - 1) // 2))
    ic = np.clip(i, k, nt - 1 - k)
    x = np.arange(-k, k + 1, dtype=float)
    # Rows of pinv give (c0, c1, c2) of y = c0 + c1 x + c2 x^2 from the 2k+1 samples.
    coef = np.linalg.pinv(np.vander(x, 3, increasing=True))
    rows = np.arange(s.shape[0])[:, None]
    off = np.zeros(s.shape[0])
    for sweep in range(2 if k > 1 else 1):
        # With k > 1 the window is re-centred once on the first vertex: the largest noisy
        # sample need not be at the centre of the underlying peak.
        if sweep:
            ic = np.clip(ic + np.rint(off).astype(int), k, nt - 1 - k)
        y = s[rows, ic[:, None] + np.arange(-k, k + 1)[None, :]]
        c0, c1, c2 = np.einsum("bj,cj->cb", y, coef)
        with np.errstate(divide="ignore", invalid="ignore"):
            off = np.where(c2 < 0, -0.5 * c1 / c2, 0.0)
        off = np.clip(off, -k, k)
    peak = np.where(c2 < 0, c0 + c1 * off + c2 * off**2, y[:, k])
    # At the record's ends there is no bracketing sample: keep the sample itself.
    edge = (i < k) | (i > nt - 1 - k)
    off = np.where(edge, 0.0, off)
    peak = np.where(edge, s[np.arange(s.shape[0]), np.clip(i, 0, nt - 1)], peak)
    time = t0 + (np.where(edge, i, ic) + off) * dt
    return time, peak


def _crossing(s: np.ndarray, j: np.ndarray, level: np.ndarray, t0: float,
              dt: float) -> np.ndarray:
    """Time where the segment between samples j and j+1 crosses ``level`` (linear)."""
    rows = np.arange(s.shape[0])
    nt = s.shape[-1]
    jc = np.clip(j, 0, nt - 2)
    a, b = s[rows, jc], s[rows, jc + 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.clip((level - a) / (b - a), 0.0, 1.0)
    return t0 + (jc + frac) * dt


def pulse_features(signal: ArrayLike, t: ArrayLike, *, threshold: float = 0.5,
                   min_delay: float | ArrayLike = 0.0, guard_widths: float = 2.0,
                   decay: float = 0.1, fit_half_width: int = 1) -> PulseFeatures:
    """Incident and reflected peaks of pulse records (rule in the module docstring).

    Parameters
    ----------
    signal : array_like, shape (..., nt)
        Records, e.g. dynamic sensor forces (N) or integrated MsS voltages.
    t : array_like, shape (nt,)
        Uniform sample times, s.
    threshold : float
        Fraction (0, 1] of the record's global maximum that starts the incident pulse.
    min_delay : float or array_like broadcastable to (...)
        Earliest reflection after the incident peak, s (e.g. half the expected round trip
        to the wall, see :func:`expected_round_trip`).
    guard_widths : float
        The reflection is searched no earlier than this many incident FWHMs after the
        incident peak.
    decay : float
        The reflection is searched only after the record falls below this fraction of the
        incident peak.
    fit_half_width : int
        Peaks are refined by a least-squares parabola through 2 k + 1 samples, k this value
        (1: interpolation through three samples; for noisy records take about a quarter of
        the FWHM in samples).

    Returns
    -------
    PulseFeatures
        Arrays of the batch shape (...).
    """
    s = np.asarray(signal, dtype=float)
    require(s.ndim >= 1, "signal must have shape (..., nt)")
    t = np.asarray(t, dtype=float)
    nt = s.shape[-1]
    dt = _check_time(t, nt)
    require(0.0 < threshold <= 1.0, f"threshold must be in (0, 1], got {threshold}")
    require(0.0 < decay < 1.0, f"decay must be in (0, 1), got {decay}")
    require(guard_widths >= 0.0, f"guard_widths must be >= 0, got {guard_widths}")
    require(isinstance(fit_half_width, int | np.integer) and fit_half_width >= 1,
            f"fit_half_width must be an integer >= 1, got {fit_half_width!r}")
    batch = s.shape[:-1]
    s = s.reshape(-1, nt)
    delay = np.broadcast_to(np.asarray(min_delay, dtype=float), batch).reshape(-1)
    idx = np.arange(nt)[None, :]
    t0 = float(t[0])

    gmax = s.max(axis=1)
    valid = gmax > 0
    above = s > (threshold * gmax)[:, None]
    i0 = np.argmax(above, axis=1)
    # Hysteresis: the excursion ends below threshold/2, so noise near the threshold on the
    # rising edge does not end the incident pulse early.
    below_after = (s < (0.5 * threshold * gmax)[:, None]) & (idx > i0[:, None])
    i1 = np.where(below_after.any(axis=1), np.argmax(below_after, axis=1), nt)
    in_pulse = (idx >= i0[:, None]) & (idx < i1[:, None])
    ip = np.argmax(np.where(in_pulse, s, -np.inf), axis=1)
    t_inc, f_inc = _parabolic(s, ip, t0, dt, fit_half_width)

    # Full width at half maximum of the incident pulse.
    half = 0.5 * f_inc
    low = s < half[:, None]
    left = low & (idx < ip[:, None])
    jl = np.where(left.any(axis=1), nt - 1 - np.argmax(left[:, ::-1], axis=1), -1)
    right = low & (idx > ip[:, None])
    jr = np.where(right.any(axis=1), np.argmax(right, axis=1), -1)
    t_left = _crossing(s, jl, half, t0, dt)
    t_right = _crossing(s, jr - 1, half, t0, dt)
    width = np.where((jl >= 0) & (jr >= 0), t_right - t_left, np.nan)

    # Reflection window: after min_delay, guard_widths FWHMs and the decay of the pulse.
    decayed = (s < decay * f_inc[:, None]) & (idx > ip[:, None])
    has_decay = decayed.any(axis=1)
    t_decay = t0 + np.argmax(decayed, axis=1) * dt
    t_start = np.fmax(np.fmax(t_inc + delay, t_inc + guard_widths * width), t_decay)
    tt = t[None, :]
    local_max = np.zeros_like(above)
    local_max[:, 1:-1] = (s[:, 1:-1] > s[:, :-2]) & (s[:, 1:-1] >= s[:, 2:])
    window = local_max & (tt >= t_start[:, None])
    has_ref = window.any(axis=1) & has_decay & valid
    ir = np.argmax(np.where(window, s, -np.inf), axis=1)
    t_ref, f_ref = _parabolic(s, ir, t0, dt, fit_half_width)

    nan = np.nan
    t_inc = np.where(valid, t_inc, nan)
    f_inc = np.where(valid, f_inc, nan)
    out = {
        "t_incident": t_inc,
        "f_incident": f_inc,
        "t_reflected": np.where(has_ref, t_ref, nan),
        "f_reflected": np.where(has_ref, f_ref, nan),
        "width": np.where(valid, width, nan),
    }
    return PulseFeatures(**{k: v.reshape(batch) for k, v in out.items()})


def expected_round_trip(distance_to_wall: ArrayLike, speed: ArrayLike) -> np.ndarray:
    """Time for a pulse to travel from a sensor to the wall and back, s.

    Parameters
    ----------
    distance_to_wall : array_like
        Distance from the sensor's centre to the wall, m.
    speed : array_like
        Pulse speed, m/s (e.g. :func:`msens.mechanics.longwave.soliton_speed_uncompressed`).
    """
    return 2.0 * np.asarray(distance_to_wall, dtype=float) / np.asarray(speed, dtype=float)


def centre_distance(length: ArrayLike, p_first: int, p_second: int) -> float:
    """Distance between the centres of two particles of a chain in contact, m.

    Parameters
    ----------
    length : array_like, shape (n,)
        Axial length of each particle, m (diameter for a sphere, length for a rod).
    p_first, p_second : int
        1-based particle numbers, ``p_first < p_second``.

    Notes
    -----
    Sum of half-lengths of the particles from ``p_first`` to ``p_second``; contact
    overlaps (micrometres) are neglected.
    """
    length = np.asarray(length, dtype=float)
    require(1 <= p_first < p_second <= length.size,
            f"particles must satisfy 1 <= p_first < p_second <= {length.size}, "
            f"got {p_first}, {p_second}")
    seg = length[p_first - 1:p_second]
    return float(seg.sum() - 0.5 * (seg[0] + seg[-1]))


def wave_speed(distance: float | ArrayLike, t_first: ArrayLike,
               t_second: ArrayLike) -> np.ndarray:
    """Speed of a pulse passing two sensors: distance / (t_second - t_first), m/s.

    For the incident wave ``t_first`` is the top sensor's incident peak time and
    ``t_second`` the bottom one's; for the reflected wave the order is reversed.
    """
    return np.asarray(distance, dtype=float) / (np.asarray(t_second, dtype=float)
                                                 - np.asarray(t_first, dtype=float))


#: Measured records (and the model records compared with them) are low-passed at this
#: frequency before their features are read, Hz. Solitary pulses here last ~20 µs (content
#: < 100 kHz); the filter removes the noise that would otherwise bias a peak's maximum
#: upward, and it is zero-phase, so it moves no peak time by itself.
FEATURE_CUTOFF_HZ = 250e3


def smooth(record: ArrayLike, dt: float) -> np.ndarray:
    """Zero-phase low-pass of a record (nt,) before feature extraction, at
    :data:`FEATURE_CUTOFF_HZ` (or 0.4 of the sampling rate 1/``dt``, s, if that is lower)."""
    return lowpass(np.asarray(record, dtype=float), dt, min(FEATURE_CUTOFF_HZ, 0.4 / dt),
                   order=4)


def integrated(voltage: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Running integral of voltage records (..., nt) from ``t[0]`` (trapezoids), V s: the
    record whose features a physics MsS gives (its coil voltage is a flux rate)."""
    return cumulative_trapezoid(np.asarray(voltage, dtype=float), np.asarray(t, dtype=float),
                                initial=0.0, axis=-1)


def model_features(records: ArrayLike, t: ArrayLike, *, lowpass_records: bool = False
                   ) -> PulseFeatures:
    """Features of feature records (..., nt): the one pipeline of the model's features.

    Parameters
    ----------
    records : array_like, shape (..., nt)
        Feature records: forces (N), or integrated physics MsS voltages (V s, or converted
        to newtons of sensitivity-weighted force).
    t : array_like, shape (nt,)
        Uniform sample times, s.
    lowpass_records : bool
        Low-pass every record first (:func:`smooth`), as measured records are: for the
        workflows that compare the model with measurements (``compare``, ``diagnose``);
        ``msens run`` reads the records as they are.

    Returns
    -------
    PulseFeatures
    """
    records = np.asarray(records, dtype=float)
    if lowpass_records:
        t = np.asarray(t, dtype=float)
        dt = float(t[1] - t[0])
        flat = records.reshape(-1, records.shape[-1])
        records = np.array([smooth(r, dt) for r in flat]).reshape(records.shape)
    return pulse_features(records, t)
