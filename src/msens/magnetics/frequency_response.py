"""The small-signal frequency response of one coil with eddy currents, and its interpolation.

:class:`FrequencyResponse` holds what :func:`msens.magnetics.dynamic.frequency_responses`
solves at a few frequencies; :func:`interp` evaluates it anywhere (PCHIP in log f above the
first solved frequency, the analytic low-frequency form below it) and :func:`coil_impedance`
gives Z = R + jωL(ω) of one or many coils.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import PchipInterpolator

from msens.errors import internal, require
from msens.params.units import TWO_PI


def interp(freqs: np.ndarray, values: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Complex values (n_f, ...) solved at ``freqs`` (freqs[0] = 0) at frequencies ``f``.

    Above the first nonzero frequency f1: PCHIP in log f on the real and imaginary parts
    (monotone between samples, no overshoot), held at the last value beyond the last
    frequency. Below f1 the low-frequency form of a response analytic in jω,
    v(f) = v0 + jωa − ω²b + …: Re v = v0 + (Re v1 − v0)(f/f1)², Im v = Im v1 (f/f1)
    — continuous at f1 and exact (the static value) at 0.
    """
    f = np.abs(np.asarray(f, dtype=float))
    v0, v1, f1 = values[0].real, values[1], freqs[1]
    out = np.empty(f.shape + values.shape[1:], dtype=complex)
    low = f < f1
    x = (f[low] / f1).reshape((-1,) + (1,) * (values.ndim - 1))
    out[low] = v0 + (v1.real - v0) * x**2 + 1j * v1.imag * x
    hi = ~low
    u = np.log(np.minimum(f[hi], freqs[-1]))
    lf = np.log(freqs[1:])
    if freqs.size > 2:
        out[hi] = (PchipInterpolator(lf, values[1:].real, axis=0)(u)
                   + 1j * PchipInterpolator(lf, values[1:].imag, axis=0)(u))
    else:
        out[hi] = v1
    return out


@dataclass(frozen=True)
class FrequencyResponse:
    """Small-signal frequency response of one coil of a physics MsS (eddy currents included).

    Attributes
    ----------
    particle : int
        Particle at the coil's centre.
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, increasing; frequencies[0] = 0 (the static transducer).
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers (as :attr:`Transducer.contacts`).
    villari : ndarray of complex, shape (n_f, n_c)
        S_c(ω) = ∂Λ/∂F_c phasor ratio, Wb/N (Λ per force amplitude; lag = negative phase).
    approach : ndarray of complex, shape (n_f, n_c)
        D_c(ω) = ∂Λ/∂δ_c, Wb/m.
    impedance : ndarray of complex, shape (n_f,)
        Coil impedance Z(ω) = R_dc + jωΛ(ω)/I, Ω (eddy losses in Re Z).
    resistance_ohm : float
        R_dc, Ω (copper at 20 °C, as the static transducer).
    static_inductance_H : float
        Λ/I at 0 Hz: the incremental inductance at the bias point, H.
    source : str
        Model, conductivities and mesh the numbers come from.
    offsets : ndarray, shape (n_o,), optional
        Axial coil offsets from its position, m (increasing, through 0).
    villari_by_offset, approach_by_offset : ndarray of complex, shape (n_o, n_f, n_c), optional
        ``villari`` and ``approach`` of the same coil moved by each offset (magnets and beads
        fixed), from the same harmonic source potentials; :meth:`shifted` interpolates them.
    screening : dict, optional
        How much of the eddy-current screening comes from the equivalent magnet's pole pieces
        (and magnet) and how much from the beads, JSON-ready
        (:func:`msens.magnetics.dynamic.screening_split`; of the coil at its own position).
    """

    particle: int
    frequencies: np.ndarray
    contacts: np.ndarray
    villari: np.ndarray
    approach: np.ndarray
    impedance: np.ndarray
    resistance_ohm: float
    static_inductance_H: float
    source: str = ""
    offsets: np.ndarray | None = None
    villari_by_offset: np.ndarray | None = None
    approach_by_offset: np.ndarray | None = None
    screening: dict | None = None

    def __post_init__(self) -> None:
        f = np.asarray(self.frequencies, dtype=float)
        n_f, n_c = f.size, np.asarray(self.contacts).size
        require(n_f >= 2 and f[0] == 0.0 and bool(np.all(np.diff(f) > 0)),
                "FrequencyResponse needs increasing frequencies starting at 0 Hz (>= 2)")
        internal(np.shape(self.villari) == (n_f, n_c) and np.shape(self.approach) == (n_f, n_c)
                 and np.shape(self.impedance) == (n_f,),
                 "internal: FrequencyResponse arrays must have shapes (n_f, n_c) and (n_f,)")
        if self.offsets is not None:
            n_o = np.asarray(self.offsets).size
            internal(np.shape(self.villari_by_offset) == (n_o, n_f, n_c)
                     and np.shape(self.approach_by_offset) == (n_o, n_f, n_c),
                     "internal: FrequencyResponse offset profiles must have shape "
                     "(n_o, n_f, n_c)")

    @property
    def inductance(self) -> np.ndarray:
        """Complex inductance L(ω) = Λ(ω)/I = (Z − R_dc)/(jω), H, shape (n_f,); L(0) is the
        static incremental inductance (Z(0) = R_dc carries no inductance)."""
        w = TWO_PI * np.asarray(self.frequencies, dtype=float)
        out = np.empty(w.size, dtype=complex)
        out[0] = self.static_inductance_H
        out[1:] = (np.asarray(self.impedance[1:]) - self.resistance_ohm) / (1j * w[1:])
        return out

    def shifted(self, offset: float) -> FrequencyResponse:
        """The same coil moved axially by ``offset`` (m, + toward the striker), magnets and
        beads fixed: S_c(ω), D_c(ω) by cubic interpolation of the offset profiles (real and
        imaginary parts). Z(ω) is kept, as :meth:`msens.magnetics.transducer.Transducer.shifted`
        keeps R and L (the coil's inductance changes little over a few mm)."""
        from scipy.interpolate import CubicSpline

        require(self.offsets is not None,
                "this frequency response has no offset profiles (dynamic_report(offsets=True))")
        lo, hi = float(self.offsets[0]), float(self.offsets[-1])
        require(lo <= offset <= hi,
                f"coil offset {offset} m outside the tabulated {lo:g}..{hi:g} m")

        def at(table):
            t = np.asarray(table)
            return (CubicSpline(self.offsets, t.real, axis=0)(offset)
                    + 1j * CubicSpline(self.offsets, t.imag, axis=0)(offset))

        return replace(self, villari=at(self.villari_by_offset),
                       approach=at(self.approach_by_offset))

    def villari_at(self, f: np.ndarray) -> np.ndarray:
        """S_c at frequencies ``f`` (Hz, |f| used), Wb/N, shape (n, n_c) (see :func:`interp`)."""
        return interp(np.asarray(self.frequencies, float), np.asarray(self.villari), f)

    def approach_at(self, f: np.ndarray) -> np.ndarray:
        """D_c at frequencies ``f`` (Hz), Wb/m, shape (n, n_c)."""
        return interp(np.asarray(self.frequencies, float), np.asarray(self.approach), f)

    def impedance_at(self, f: np.ndarray) -> np.ndarray:
        """Z at frequencies ``f`` (Hz), Ω, shape (n,) (:func:`coil_impedance`)."""
        return coil_impedance(self.frequencies, self.inductance, self.resistance_ohm, f)


def coil_impedance(frequencies: np.ndarray, inductance: np.ndarray,
                   resistance: float | np.ndarray, f: np.ndarray) -> np.ndarray:
    """Z = R_dc + jω L(ω) of one or many coils at frequencies ``f``, with the complex
    inductance L(ω) interpolated (it is smooth and finite at DC; Z/ω is not).

    Parameters
    ----------
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, from 0.
    inductance : ndarray of complex, shape (n_f, ...)
        L(ω) at them, H.
    resistance : float or ndarray, shape (...)
        R_dc, Ω.
    f : ndarray, shape (n,)
        Hz.

    Returns
    -------
    ndarray of complex, shape (n, ...)
        Ω.
    """
    f = np.asarray(f, dtype=float)
    ind = interp(np.asarray(frequencies, float), np.asarray(inductance), f)
    w = TWO_PI * f.reshape((-1,) + (1,) * (ind.ndim - 1))
    return resistance + 1j * w * ind


__all__ = ["FrequencyResponse", "coil_impedance", "interp"]
