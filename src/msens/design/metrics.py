"""Per-design figures of merit from the transducer core, vectorised over designs.

A design's coil signal is computed exactly as ``msens run`` computes it: the open-circuit EMF
V = -Σ_c [(∂Λ/∂F_c) dF_c/dt + (∂Λ/∂δ_c) dδ_c/dt] of both mechanisms
(:func:`msens.magnetics.emf.emf_from_rates`) for the study's wave, and the read-out
circuit of :func:`msens.readout.mss.readout` (coil R and bias-point L, winding, cable and
DAQ input capacitances, DAQ input resistance). From them:

- ``peak_emf_V``: max |EMF| (the figure ``summary.json`` reports per coil);
- ``peak_voltage_V``: max |V_DAQ| of the noise-free DAQ voltage, the EMF filtered by the
  circuit's transfer function (:func:`msens.readout.electronics.transfer_function`, by FFT on a grid
  padded by 14 decay times of the circuit's slowest pole, so the ringing of a resonance
  inside the band counts and does not wrap around);
- ``noise_rms_V``: :func:`msens.readout.mss.figure_noise_rms` (Johnson noise of the circuit,
  DAQ noise, quantisation); ``snr`` = peak_voltage_V / noise_rms_V;
- resonance, Q, DC gain and -3 dB bandwidth of the circuit (:mod:`msens.readout.electronics`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.fft

from msens.field.parts import Coil
from msens.magnetics.eddy_readout import PAD, emf_spectra
from msens.magnetics.emf import ContactRates, emf_from_rates
from msens.magnetics.frequency_response import coil_impedance
from msens.readout.electronics import (
    ElectronicsSpec,
    bandwidth,
    coil_transfer_function,
    poles,
    resonance,
    transfer_function,
)
from msens.readout.mss import figure_noise_rms, readout

#: Designs whose EMF records are formed at once (bounds memory: chunk × nt doubles).
EMF_CHUNK = 256
#: FFT padding in decay times of the slowest circuit pole (e^-14 ≈ 1e-6 of wrapped ringing).
DECAY_TIMES = 14.0


@dataclass(frozen=True)
class Wave:
    """The study's wave as a design sees it.

    Attributes
    ----------
    contacts : ndarray of int, shape (n_c,)
        Contacts the rates belong to (the transducer's).
    rates : ContactRates
        dF_c/dt and dδ_c/dt of those contacts, shape (nt, n_c) each.
    precompression_N, precompression_max_N : float
        Magnetic static compression at the sensor: mean over c_{p-2}..c_{p+1} and max |.|.
    wave_speed_change : float
        Relative change of the solitary-wave speed at the sensor the magnets cause.
    """

    contacts: np.ndarray
    rates: ContactRates
    precompression_N: float
    precompression_max_N: float
    wave_speed_change: float


def _circuit_figures(coil: Coil, resistance: float, inductance: float,
                     electronics: ElectronicsSpec) -> dict:
    circuit = readout(coil, resistance, inductance, electronics)
    f0, q = resonance(circuit)
    return {"circuit": circuit, "resonance_Hz": f0, "quality_factor": q,
            "bandwidth_Hz": bandwidth(circuit), "noise_rms_V": figure_noise_rms(circuit,
                                                                              electronics),
            "winding_capacitance_F": circuit.winding_capacitance,
            "decay_s": 1.0 / float(np.min(-poles(circuit).real))}


def _circuits(coils: Sequence[Coil], resistance: np.ndarray, inductance: np.ndarray,
              electronics: ElectronicsSpec) -> tuple[list[tuple], dict]:
    """Each design's circuit key, and the circuit figures once per distinct circuit (designs
    that differ only in their axial offset share one)."""
    keys = [(round(float(r), 12), round(float(ind), 15), c.turns, c.length, c.inner_radius,
             c.wire.name, c.packing_factor) for c, r, ind in zip(coils, resistance, inductance,
                                                                 strict=True)]
    circuits: dict = {}
    for k, c, r, ind in zip(keys, coils, resistance, inductance, strict=True):
        if k not in circuits:
            circuits[k] = _circuit_figures(c, float(r), float(ind), electronics)
    return keys, circuits


def design_rows(coils: Sequence[Coil], resistance: np.ndarray, inductance: np.ndarray,
                sensitivity_villari: np.ndarray, dlambda_dapproach: np.ndarray, wave: Wave,
                electronics: ElectronicsSpec) -> list[dict]:
    """Metrics of coil designs, one dict per design.

    Parameters
    ----------
    coils : sequence of Coil, length n_d
    resistance, inductance : ndarray, shape (n_d,)
        Ω and H (bias-point incremental inductance).
    sensitivity_villari : ndarray, shape (n_d, n_c)
        ∂Λ/∂F_c, Wb/N.
    dlambda_dapproach : ndarray, shape (n_d, n_c)
        ∂Λ/∂δ_c, Wb/m.
    wave : Wave
    electronics : ElectronicsSpec
    """
    t = wave.rates.t
    nt = t.size
    dt = float(t[1] - t[0])
    keys, circuits = _circuits(coils, resistance, inductance, electronics)
    decay = max(cf["decay_s"] for cf in circuits.values())
    n_fft = scipy.fft.next_fast_len(nt + math.ceil(DECAY_TIMES * decay / dt), real=True)
    freq = np.fft.rfftfreq(n_fft, dt)
    for cf in circuits.values():
        cf["transfer"] = transfer_function(cf["circuit"], freq)
    s_app = dlambda_dapproach  # Wb/m
    rows: list[dict] = []
    for lo in range(0, len(coils), EMF_CHUNK):
        hi = min(lo + EMF_CHUNK, len(coils))
        e = emf_from_rates(wave.rates, sensitivity_villari[lo:hi], s_app[lo:hi])
        spectrum = scipy.fft.rfft(e, n_fft, axis=1)
        for k in range(lo, hi):
            cf = circuits[keys[k]]
            v = scipy.fft.irfft(spectrum[k - lo] * cf["transfer"], n_fft)[:nt]
            rows.append(_row(coils[k], float(resistance[k]), float(inductance[k]), cf,
                             sensitivity_villari[k], dlambda_dapproach[k], e[k - lo], v, wave))
    return rows


def _row(coil: Coil, resistance: float, inductance: float, cf: dict, villari: np.ndarray,
         approach: np.ndarray, emf: np.ndarray, voltage: np.ndarray, wave: Wave) -> dict:
    peak_v = float(np.max(np.abs(voltage)))
    return {
        "outer_radius_m": coil.outer_radius,
        "resistance_ohm": resistance, "inductance_H": inductance,
        "winding_capacitance_F": cf["winding_capacitance_F"],
        "resonance_Hz": cf["resonance_Hz"], "quality_factor": cf["quality_factor"],
        "bandwidth_Hz": cf["bandwidth_Hz"], "noise_rms_V": cf["noise_rms_V"],
        "sensitivity_villari_Wb_per_N": float(np.sum(villari)),
        "dLambda_dapproach_Wb_per_m": float(np.sum(approach)),
        "peak_emf_V": float(np.max(np.abs(emf))),
        "peak_voltage_V": peak_v, "snr": peak_v / cf["noise_rms_V"],
        "precompression_N": wave.precompression_N,
        "precompression_max_N": wave.precompression_max_N,
        "wave_speed_change": wave.wave_speed_change,
    }


#: Designs whose eddy-current spectra are formed at once (bounds memory: chunk × bins × n_c).
SPECTRUM_CHUNK = 16


def dynamic_design_rows(coils: Sequence[Coil], resistance: np.ndarray, inductance: np.ndarray,
                        frequencies: np.ndarray, villari: np.ndarray, approach: np.ndarray,
                        inductance_w: np.ndarray, wave: Wave,
                        electronics: ElectronicsSpec) -> list[dict]:
    """Metrics of coil designs with eddy currents, one dict per design.

    The EMF and the DAQ voltage are those of ``msens run`` with eddy currents
    (:func:`msens.readout.mss.mss_signals`): the contact rates' spectra times the
    complex sensitivities (:func:`msens.magnetics.eddy_readout.emf_spectra`), then the read-out
    circuit with the coil's series impedance Z(ω) = R + jωL(ω)
    (:func:`msens.readout.electronics.coil_transfer_function`), on the run's FFT length
    (:data:`msens.readout.mss.PAD`). Resonance, Q, bandwidth and noise are the static
    circuit's (R, bias-point L), as ``summary.json`` reports them.

    Parameters
    ----------
    coils : sequence of Coil, length n_d
    resistance, inductance : ndarray, shape (n_d,)
        Ω and H (static bias-point incremental inductance: the circuit figures).
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, from 0.
    villari, approach : ndarray of complex, shape (n_d, n_f, n_c)
        S_c(ω), Wb/N, and D_c(ω), Wb/m, of each design.
    inductance_w : ndarray of complex, shape (n_d, n_f)
        L(ω) of each design, H.
    wave : Wave
    electronics : ElectronicsSpec
    """
    t = wave.rates.t
    nt = t.size
    dt = float(t[1] - t[0])
    n = scipy.fft.next_fast_len(math.ceil(PAD * nt), real=True)
    f = np.fft.rfftfreq(n, dt)
    force = scipy.fft.rfft(wave.rates.force, n, axis=0)
    app = scipy.fft.rfft(wave.rates.approach, n, axis=0)
    keys, circuits = _circuits(coils, resistance, inductance, electronics)
    rows: list[dict] = []
    for lo in range(0, len(coils), SPECTRUM_CHUNK):
        sl = slice(lo, min(lo + SPECTRUM_CHUNK, len(coils)))
        e_hat = emf_spectra(frequencies, np.moveaxis(villari[sl], 1, 0),
                            np.moveaxis(approach[sl], 1, 0), f, force, app)
        z = coil_impedance(frequencies, np.asarray(inductance_w[sl]).T, resistance[sl], f)
        for j, k in enumerate(range(sl.start, sl.stop)):
            cf = circuits[keys[k]]
            h = coil_transfer_function(cf["circuit"], f, z[:, j])
            e = scipy.fft.irfft(e_hat[:, j], n)[:nt]
            v = scipy.fft.irfft(h * e_hat[:, j], n)[:nt]
            rows.append(_row(coils[k], float(resistance[k]), float(inductance[k]), cf,
                             villari[k, 0].real, approach[k, 0].real, e, v, wave))
    return rows


__all__ = ["DECAY_TIMES", "EMF_CHUNK", "SPECTRUM_CHUNK", "Wave", "design_rows",
           "dynamic_design_rows"]
