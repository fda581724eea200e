"""Checks that a measured waveform carries a signal the model can be held against.

``compare`` and ``diagnose`` both refuse, before fitting anything, a file whose records
cannot be a measurement of the study's chain: shots that lack a channel, amplitudes no
instrument records, no pulse above the noise, a record whose sign is inverted (coil leads
or probe swapped) or whose time axis is scaled (a time unit other than seconds). Without
these checks such a file gives confident nonsense: metrics of noise, or a "diagnosis" of a
physical effect that is really a wiring or unit mistake.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import fftconvolve

from msens.errors import InputError
from msens.io.waveform import Waveform

#: Range of a channel's largest absolute value, V. Below 1e-15 V no digitiser resolves a
#: signal (a femtovolt is far below any amplifier's noise); above 1e6 V no sensor output
#: is meant. Outside, the numbers are a scaling mistake, and arithmetic on them under- or
#: overflows.
AMPLITUDE_RANGE_V = (1e-15, 1e6)
#: Smallest ratio of a record's largest excursion to its noise that counts as a pulse.
#: Gaussian noise alone reaches about 4-5 sigma in 10^4-10^5 samples.
MIN_SNR = 8.0
#: A record is called inverted when its cross-correlation with the model reaches this many
#: times further negative than positive. A bipolar pulse (an MsS voltage, dF/dt) correlates
#: with itself at +1 and with its shifted copy at about -1/2, so a ratio of 1.5 separates
#: the two orientations with margin.
INVERSION_RATIO = 1.5
#: Largest ratio between the measured and the model pulse's duration (full width at half
#: maximum of the largest excursion) not called a time-scale error. Physics changes a
#: pulse's duration weakly (the solitary wave's width is about five bead diameters at any
#: amplitude), so a factor
#: 1.6 is beyond what a wrong precompression or damping can do, while a wrong time unit or
#: sample rate gives factors of 2 to 1e6.
MAX_DURATION_RATIO = 1.6


def check_shots(waveform: Waveform, source: str) -> None:
    """Every shot (``#repeat``) must hold the same sensors as the first.

    Raises
    ------
    InputError
        Naming the shot and the channel it lacks or adds.
    """
    shots: dict[int, set[str]] = {}
    for ch in waveform.channels:
        shots.setdefault(ch.repeat, set()).add(f"{ch.kind}@{ch.particle}")
    repeats = sorted(shots)
    if repeats != list(range(1, len(repeats) + 1)):
        raise InputError(f"{source}: shots must be numbered #1 (no suffix), #2, ... without "
                         f"gaps; the channels give shots {repeats}")
    first = shots[repeats[0]]
    for r in repeats[1:]:
        if shots[r] != first:
            missing = sorted(first - shots[r]) or sorted(shots[r] - first)
            raise InputError(f"{source}: shot #{r} has channels {sorted(shots[r])}, shot #1 "
                             f"has {sorted(first)} (differs in {', '.join(missing)}); every "
                             "shot must record the same sensors")


def check_amplitudes(waveform: Waveform, source: str) -> None:
    """Each channel's largest absolute value must lie in :data:`AMPLITUDE_RANGE_V`."""
    lo, hi = AMPLITUDE_RANGE_V
    for j, ch in enumerate(waveform.channels):
        peak = float(np.max(np.abs(waveform.data[:, j]))) if waveform.data.size else 0.0
        if not lo <= peak <= hi:
            raise InputError(f"{source}: channel {ch.name} peaks at {peak:.3g} V; a recorded "
                             f"voltage lies between {lo:g} and {hi:g} V (a scaling mistake, "
                             "or an empty channel?)")


def noise_level(values: np.ndarray) -> float:
    """Standard deviation of a record's white noise, from its sample-to-sample differences
    (median absolute deviation, robust to the pulse: a pulse sampled at MHz rates changes
    little from one sample to the next, wherever it lies in the record)."""
    d = np.diff(np.asarray(values, dtype=float))
    return float(np.median(np.abs(d - np.median(d))) / 0.6745 / np.sqrt(2.0))


def check_pulses(waveform: Waveform, source: str) -> None:
    """Each channel must rise above its noise by :data:`MIN_SNR`: a record of noise only
    has no pulse to compare (metrics of noise are not a comparison)."""
    for j, ch in enumerate(waveform.channels):
        v = waveform.data[:, j]
        excursion = float(np.max(np.abs(v - np.median(v))))
        noise = noise_level(v)
        if not excursion > MIN_SNR * noise:
            raise InputError(f"{source}: channel {ch.name} has no pulse: its largest excursion "
                             f"{excursion:.3g} V is not above {MIN_SNR:g} x its noise "
                             f"({noise:.3g} V)")


def _baseline_free(values: np.ndarray) -> np.ndarray:
    head = values[: max(1, values.size // 20)]  # the first 5 %: before the pulse arrives
    return values - float(np.mean(head))


def pulse_width(values: np.ndarray, dt: float) -> float:
    """Full width at half maximum of a record's largest excursion from its median, s (a
    pulse's duration; the median is the baseline of a record that is mostly quiet)."""
    v = np.asarray(values, dtype=float)
    v = v - float(np.median(v))
    k = int(np.argmax(np.abs(v)))
    level = 0.5 * v[k]
    if level == 0.0:
        return float("nan")
    above = np.sign(level) * v > abs(level)
    left = k
    while left > 0 and above[left - 1]:
        left -= 1
    right = k
    while right < v.size - 1 and above[right + 1]:
        right += 1
    return float((right - left + 1) * dt)


def _slope(values: np.ndarray, span: int) -> np.ndarray:
    """Differences of a record smoothed over ``span`` samples (a moving mean): the pulses'
    edges, without the plateaus, baselines and drifts a record may hold between them."""
    v = np.asarray(values, dtype=float)
    if span > 1:
        v = np.convolve(v, np.ones(span) / span, mode="valid")
    return np.diff(v)


def orientation(measured: np.ndarray, model: np.ndarray, span: int = 1) -> float:
    """Ratio of the most negative to the most positive cross-correlation of the slopes of
    two records on one time grid (> :data:`INVERSION_RATIO`: the measured record is upside
    down); ``span`` samples of smoothing first."""
    a, b = _slope(measured, span), _slope(model, span)
    c = fftconvolve(a, b[::-1], mode="full")
    top = float(np.max(c))
    return float(-np.min(c) / top) if top > 0.0 else float("inf")


def check_against_model(channel: str, source: str, t_data: np.ndarray, data: np.ndarray,
                        t_model: np.ndarray, model: np.ndarray) -> None:
    """Refuse a measured record that is the model's upside down or on a scaled time axis.

    Parameters
    ----------
    channel, source : str
        Names for the message (channel, file).
    t_data, data : ndarray, shape (nd,)
        The measured record, its time axis in s.
    t_model, model : ndarray, shape (nt,)
        The model's record of the same channel in the same kind of quantity (a voltage
        shape), on a uniform time axis in s.
    """
    dt_model = float(t_model[1] - t_model[0])
    dt_data = float(t_data[1] - t_data[0])
    w_model, w_data = pulse_width(model, dt_model), pulse_width(data, dt_data)
    if np.isfinite(w_model) and np.isfinite(w_data) and w_model > 0 and w_data > 0:
        ratio = w_data / w_model
        if not 1.0 / MAX_DURATION_RATIO <= ratio <= MAX_DURATION_RATIO:
            raise InputError(
                f"{source}: channel {channel}'s pulse lasts {w_data * 1e6:.3g} us where the "
                f"model's lasts {w_model * 1e6:.3g} us, {ratio:.3g} times as long: the time "
                "axis looks scaled (time_s must be in seconds; check the file's time unit and "
                "sample rate, or the study's chain)")
    # on the model's grid, over the span both cover
    inside = (t_model >= t_data[0]) & (t_model <= t_data[-1])
    if inside.sum() < 8:
        return
    resampled = np.interp(t_model[inside], t_data, data)
    span = max(1, int(0.25 * w_model / dt_model)) if np.isfinite(w_model) else 1
    ratio = orientation(resampled, model[inside], span)
    if ratio > INVERSION_RATIO:
        raise InputError(
            f"{source}: channel {channel} looks inverted: it matches the model upside down "
            f"({ratio:.2g} times better than upright); swap the coil or probe leads, or "
            "multiply the channel by -1")
