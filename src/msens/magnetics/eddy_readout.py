"""EMF spectra with eddy currents: the contact rates through S_c(ω) and D_c(ω).

The frequency-domain EMF of :mod:`msens.magnetics.dynamic`'s responses: the EMF spectrum of
one or many coils (:func:`emf_spectra`, for coil design) and each mechanism's EMF alone
(:func:`mechanism_emfs`, for the run's physics summary). The DAQ record of a coil with eddy
currents is the one physics-MsS read-out, :func:`msens.readout.mss.mss_signals` with the
coil's frequency response.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft, rfftfreq

from msens.magnetics.frequency_response import FrequencyResponse, interp
from msens.readout.mss import PAD, ContactRates, emf_spectrum


def emf_spectra(frequencies: np.ndarray, villari: np.ndarray, approach: np.ndarray,
                f: np.ndarray, force_rate: np.ndarray, approach_rate: np.ndarray) -> np.ndarray:
    """EMF(ω) = −Σ_c [S_c(ω) Ḟ_c(ω) + D_c(ω) δ̇_c(ω)] of one or many coils.

    Parameters
    ----------
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, from 0.
    villari, approach : ndarray of complex, shape (n_f, ..., n_c)
        S_c (Wb/N) and D_c (Wb/m) at them, interpolated to ``f`` by :func:`interp`.
    f : ndarray, shape (n,)
        Hz.
    force_rate, approach_rate : ndarray of complex, shape (n, n_c)
        Spectra of dF_c/dt (N/s per bin) and dδ_c/dt (m/s per bin), the coils' contacts.

    Returns
    -------
    ndarray of complex, shape (n, ...)
    """
    freqs = np.asarray(frequencies, float)
    return emf_spectrum(interp(freqs, np.asarray(villari), f),
                        interp(freqs, np.asarray(approach), f), force_rate, approach_rate)


def mechanism_emfs(response: FrequencyResponse, rates: ContactRates,
                   pad: float = PAD) -> dict[str, np.ndarray]:
    """Each mechanism's open-circuit EMF alone, with eddy currents, V.

    Parameters
    ----------
    response : FrequencyResponse
    rates : ContactRates
        Rates of ``response.contacts`` on uniform times.
    pad : float
        FFT length ≥ ``pad`` × nt, as :func:`msens.readout.mss.mss_signals`.

    Returns
    -------
    dict
        ``"villari"`` and ``"approach"``: ndarray, shape (nt,); they add up to the EMF of
        :func:`msens.readout.mss.mss_signals` with this response.
    """
    t = np.asarray(rates.t)
    dt = (t[-1] - t[0]) / (t.size - 1)
    n = next_fast_len(math.ceil(pad * t.size), real=True)
    f = rfftfreq(n, dt)
    force = rfft(rates.force, n, axis=0)
    approach = rfft(rates.approach, n, axis=0)
    s, d = response.villari_at(f), response.approach_at(f)
    return {"villari": irfft(emf_spectrum(s, d, force, 0.0 * approach), n)[:t.size],
            "approach": irfft(emf_spectrum(s, d, 0.0 * force, approach), n)[:t.size]}


__all__ = ["PAD", "emf_spectra", "mechanism_emfs"]
