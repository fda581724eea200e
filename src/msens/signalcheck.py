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
#: A record is called inverted when its cross-correlation with the model reaches this many
#: times further negative than positive. A bipolar pulse (an MsS voltage, dF/dt) correlates
#: with itself at +1 and with its shifted copy at about -1/2, so a ratio of 1.5 separates
#: the two orientations with margin.
INVERSION_RATIO = 1.5
#: Largest ratio between the measured and the model pulse's duration (autocorrelation
#: half-width) not called a time-scale error. Physics changes a pulse's duration weakly
#: (the solitary wave's width is about five bead diameters at any amplitude), so a factor
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


def _baseline_free(values: np.ndarray) -> np.ndarray:
    head = values[: max(1, values.size // 20)]  # the first 5 %: before the pulse arrives
    return values - float(np.mean(head))


def half_width(values: np.ndarray, dt: float) -> float:
    """Autocorrelation half-width of a record, s: the first lag at which its normalised
    autocorrelation falls below 1/2 (a pulse's duration scale; white noise adds at lag 0
    only)."""
    v = _baseline_free(np.asarray(values, dtype=float))
    ac = fftconvolve(v, v[::-1], mode="full")[v.size - 1:]
    if not ac[0] > 0.0:
        return float("nan")
    below = np.flatnonzero(ac[1:] < 0.5 * ac[0])
    return float((below[0] + 1) * dt) if below.size else float("nan")


def orientation(measured: np.ndarray, model: np.ndarray) -> float:
    """Ratio of the most negative to the most positive cross-correlation of two records on
    one time grid (> :data:`INVERSION_RATIO`: the measured record is upside down)."""
    a, b = _baseline_free(measured), _baseline_free(model)
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
    w_model, w_data = half_width(model, dt_model), half_width(data, dt_data)
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
    ratio = orientation(resampled, model[inside])
    if ratio > INVERSION_RATIO:
        raise InputError(
            f"{source}: channel {channel} looks inverted: it matches the model upside down "
            f"({ratio:.2g} times better than upright); swap the coil or probe leads, or "
            "multiply the channel by -1")
