"""Coil signals with eddy currents: the contact rates through S_c(ω), D_c(ω) and Z(ω) by FFT.

The frequency-domain read-out of :mod:`msens.magnetics.dynamic`'s responses: the EMF spectrum
of one or many coils (:func:`emf_spectra`, shared by ``msens run`` and coil design), each
mechanism's EMF alone (:func:`mechanism_emfs`) and the DAQ record (:func:`dynamic_signals`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft, rfftfreq

from msens.errors import require
from msens.magnetics.emf import ContactRates, contact_forces_of, contact_rates
from msens.magnetics.frequency_response import FrequencyResponse, interp
from msens.magnetics.mss import MssRecord
from msens.magnetics.transducer import Transducer
from msens.mechanics.hertz import hertz_approach
from msens.readout.electronics import ReadoutCircuit, coil_transfer_function
from msens.readout.noise import NoiseModel, add_readout_noise

#: FFT length of the frequency-domain read-out in record lengths (zero padding: the circuit's
#: ring-down after the record must fit in it; run and design use the same).
PAD = 2.0


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
    s, d = interp(freqs, np.asarray(villari), f), interp(freqs, np.asarray(approach), f)
    shape = (s.shape[0],) + (1,) * (s.ndim - 2) + (s.shape[-1],)
    return -(np.sum(s * np.reshape(force_rate, shape), axis=-1)
             + np.sum(d * np.reshape(approach_rate, shape), axis=-1))


def emf_spectrum(response: FrequencyResponse, f: np.ndarray, force_rate: np.ndarray,
                 approach_rate: np.ndarray) -> np.ndarray:
    """EMF(ω) of one coil (:func:`emf_spectra`), shape (n,).

    Parameters
    ----------
    response : FrequencyResponse
    f : ndarray, shape (n,)
        Hz.
    force_rate, approach_rate : ndarray of complex, shape (n, n_c)
        Spectra of dF_c/dt (N/s per bin) and dδ_c/dt (m/s per bin), the record's contacts.
    """
    return emf_spectra(response.frequencies, response.villari, response.approach, f,
                       force_rate, approach_rate)


def mechanism_emfs(response: FrequencyResponse, rates: ContactRates,
                   pad: float = PAD) -> dict[str, np.ndarray]:
    """Each mechanism's open-circuit EMF alone, with eddy currents, V.

    Parameters
    ----------
    response : FrequencyResponse
    rates : ContactRates
        Rates of ``response.contacts`` on uniform times.
    pad : float
        FFT length ≥ ``pad`` × nt, as :func:`dynamic_signals`.

    Returns
    -------
    dict
        ``"villari"`` and ``"approach"``: ndarray, shape (nt,); they add up to the EMF of
        :func:`dynamic_signals`.
    """
    t = np.asarray(rates.t)
    dt = (t[-1] - t[0]) / (t.size - 1)
    n = next_fast_len(math.ceil(pad * t.size), real=True)
    f = rfftfreq(n, dt)
    force = rfft(rates.force, n, axis=0)
    approach = rfft(rates.approach, n, axis=0)
    return {"villari": irfft(emf_spectrum(response, f, force, 0.0 * approach), n)[:t.size],
            "approach": irfft(emf_spectrum(response, f, 0.0 * force, approach), n)[:t.size]}


def dynamic_signals(transducer: Transducer, response: FrequencyResponse,
                    circuit: ReadoutCircuit, t: np.ndarray, force: np.ndarray,
                    sample_rate: float, *, approach: np.ndarray | None = None,
                    columns: np.ndarray | None = None, pad: float = PAD,
                    noise: NoiseModel | None = None,
                    rng: np.random.Generator | int | None = None) -> MssRecord:
    """Coil signals of one physics MsS with eddy currents: the frequency-domain read-out.

    The contact force and approach rates (as :func:`msens.magnetics.mss.mss_signals`) are
    zero-padded to ``pad`` × their length and Fourier transformed; the EMF spectrum is
    :func:`emf_spectrum` and the DAQ voltage that times the read-out transfer function with
    the coil's impedance Z(ω) (:func:`msens.readout.electronics.coil_transfer_function`); inverse
    FFT. The circuit starts at rest and the EMF is zero before ``t[0]`` (chain histories
    start static). Noise (optional) is the read-out's, with the coil's Johnson noise from
    4kT Re Z(f) (:func:`msens.readout.noise.add_readout_noise`). With σ = 0 this is
    :func:`~msens.magnetics.mss.mss_signals` up to its first-order-hold EMF (agreement to
    ~(ωΔt)²/12 at the signal frequencies).

    Parameters
    ----------
    transducer : Transducer
        Contacts and Hertz stiffness (and the static sensitivities of ``weighted_force``).
    response : FrequencyResponse
        Of the same coil (same contacts).
    circuit : ReadoutCircuit
        Winding capacitance, cable and DAQ (its R and L are replaced by Z(ω)).
    t : ndarray, shape (nt,)
        Uniform chain output times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    sample_rate : float
        DAQ rate, Hz: the voltage is linearly interpolated from the chain's grid to the DAQ
        instants t[0] + k/sample_rate (exact where the DAQ samples at the chain's rate).
    approach, columns
        As :func:`~msens.magnetics.mss.mss_signals` (no ``static``: the EMF needs rates only).
    pad : float
        FFT length ≥ ``pad`` × nt (> 1: the circuit's ring-down must fit in the padding).
    noise : NoiseModel, optional
    rng : numpy.random.Generator or int, optional
        Seed or generator of the noise (None = seed 0).

    Returns
    -------
    MssRecord
        ``flux`` is −∫ EMF dt (eddy currents included).
    """
    from scipy.integrate import cumulative_trapezoid

    contacts = np.asarray(transducer.contacts, dtype=int)
    require(np.array_equal(contacts, np.asarray(response.contacts)),
            "transducer and frequency response describe different contacts")
    require(pad > 1, f"pad must be > 1, got {pad}")
    t = np.asarray(t, dtype=float)
    fc = contact_forces_of(force, contacts, columns)
    stiff = transducer.contact_stiffness
    delta = (hertz_approach(fc, stiff) if approach is None
             else contact_forces_of(approach, contacts, columns))
    rates = contact_rates(t, fc, contacts, stiff, columns=contacts, approach=delta,
                          equivalent=transducer.equivalent_approach)
    dt = (t[-1] - t[0]) / (t.size - 1)
    require(bool(np.allclose(np.diff(t), dt, rtol=1e-6, atol=0.0)),
            "chain times must be uniformly spaced")
    n = next_fast_len(math.ceil(pad * t.size), real=True)
    f = rfftfreq(n, dt)
    e_hat = emf_spectrum(response, f, rfft(rates.force, n, axis=0),
                         rfft(rates.approach, n, axis=0))
    h = coil_transfer_function(circuit, f, response.impedance_at(f))
    e = irfft(e_hat, n)[:t.size]
    v = irfft(h * e_hat, n)[:t.size]
    n_daq = math.floor((t[-1] - t[0]) * sample_rate * (1 + 1e-12)) + 1
    t_daq = t[0] + np.arange(n_daq) / sample_rate
    flux = -cumulative_trapezoid(e, t, initial=0.0)
    total = float(np.sum(transducer.sensitivity("both")))
    voltage = np.interp(t_daq, t, v)
    if noise is not None:
        voltage = add_readout_noise(voltage, circuit, noise, sample_rate, rng=rng,
                                    coil_impedance=response.impedance_at)
    return MssRecord(t=t, flux=flux, weighted_force=flux / total if total else flux * np.nan,
                     emf=e, t_daq=t_daq, voltage=voltage, circuit=circuit, sensitivity=total)


__all__ = ["PAD", "dynamic_signals", "emf_spectra", "emf_spectrum", "mechanism_emfs"]
