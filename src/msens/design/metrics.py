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
- resonance, Q and -3 dB bandwidth of the circuit, in closed form for all designs at once
  (:func:`msens.readout.electronics.resonance_figures`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.fft
from scipy.interpolate import PchipInterpolator

from msens.errors import internal, require
from msens.field.parts import Coil
from msens.magnetics.eddy_readout import PAD, emf_spectra
from msens.magnetics.emf import ContactRates, emf_from_rates
from msens.magnetics.frequency_response import interp
from msens.parallel import thread_map
from msens.params.units import TWO_PI
from msens.readout.coil import winding_capacitance
from msens.readout.electronics import (
    ElectronicsSpec,
    ReadoutCircuit,
    ResonanceFigures,
    coil_transfer_functions,
    resonance_figures,
)
from msens.readout.mss import figure_noise_rms_of, readout

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


@dataclass(frozen=True)
class _Circuits:
    """The designs' read-out circuits and their figures, one entry per design.

    Attributes
    ----------
    load : ReadoutCircuit
        The first design's circuit: the cable and DAQ input all designs share.
    resistance, inductance, winding_capacitance : ndarray, shape (n_d,)
        R (Ω), bias-point L (H) and C_w (F) of each design's circuit
        (:func:`msens.readout.mss.readout`).
    figures : ResonanceFigures
        Resonance, Q, bandwidth and slowest decay, arrays of shape (n_d,) (closed form:
        the sweep's circuits are second order, R_c = 0).
    noise_rms : ndarray, shape (n_d,)
        :func:`msens.readout.mss.figure_noise_rms`, V.
    """

    load: ReadoutCircuit
    resistance: np.ndarray
    inductance: np.ndarray
    winding_capacitance: np.ndarray
    figures: ResonanceFigures
    noise_rms: np.ndarray


def _circuits(coils: Sequence[Coil], resistance: np.ndarray, inductance: np.ndarray,
              electronics: ElectronicsSpec) -> _Circuits:
    """Each design's circuit (:func:`msens.readout.mss.readout`; the winding capacitance
    computed once per winding) and its figures, vectorised over designs."""
    resistance = np.asarray(resistance, dtype=float)
    inductance = np.asarray(inductance, dtype=float)
    for values, name in ((resistance, "resistance"), (inductance, "inductance")):
        require(bool(np.all(np.isfinite(values) & (values > 0))),
                f"every design's coil {name} must be finite and > 0, got {values.min()}")
    # designs that differ in their offset alone share a winding
    windings = [(c.turns, c.length, c.inner_radius, c.wire.name, c.packing_factor)
                for c in coils]
    per_winding = {w: winding_capacitance(c)
                   for w, c in dict(zip(windings, coils, strict=True)).items()}
    c_w = np.array([per_winding[w] for w in windings])
    load = readout(coils[0], float(resistance[0]), float(inductance[0]), electronics)
    internal(load.cable_resistance == 0.0,
             "internal: a coil sweep's read-out circuit with a cable resistance")
    capacitance = c_w + load.load_capacitance
    return _Circuits(load, resistance, inductance, c_w,
                     resonance_figures(resistance, inductance, capacitance,
                                       load.input_conductance),
                     figure_noise_rms_of(capacitance, electronics))


def design_rows(coils: Sequence[Coil], resistance: np.ndarray, inductance: np.ndarray,
                sensitivity_villari: np.ndarray, dlambda_dapproach: np.ndarray, wave: Wave,
                electronics: ElectronicsSpec, threads: int = 1) -> list[dict]:
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
    threads : int
        Threads the chunks of designs run on (:func:`msens.parallel.thread_map`).
    """
    t = wave.rates.t
    nt = t.size
    dt = float(t[1] - t[0])
    cs = _circuits(coils, resistance, inductance, electronics)
    decay = float(np.max(cs.figures.decay_s))
    n_fft = scipy.fft.next_fast_len(nt + math.ceil(DECAY_TIMES * decay / dt), real=True)
    freq = np.fft.rfftfreq(n_fft, dt)
    s = 2j * np.pi * freq
    s_app = dlambda_dapproach  # Wb/m

    def chunk(sl: slice) -> list[dict]:
        e = emf_from_rates(wave.rates, sensitivity_villari[sl], s_app[sl])
        spectrum = scipy.fft.rfft(e, n_fft, axis=1)
        # the chunk's transfer functions at once, the spectra divided in the same pass (a
        # sweep may have as many distinct circuits as designs, so none is kept)
        z_s = cs.resistance[sl, None] + s * cs.inductance[sl, None]
        spectrum = coil_transfer_functions(cs.load, cs.winding_capacitance[sl], freq, z_s,
                                           spectrum)
        peak_v = _peaks(scipy.fft.irfft(spectrum, n_fft, axis=1)[:, :nt])
        peak_e = _peaks(e)
        return [_row(coils[k], k, cs, sensitivity_villari[k], dlambda_dapproach[k],
                     float(peak_e[j]), float(peak_v[j]), wave)
                for j, k in enumerate(range(sl.start, sl.stop))]

    return _chunked(chunk, len(coils), EMF_CHUNK, threads)


def _chunked(fn, n: int, size: int, threads: int) -> list[dict]:
    """``fn``'s rows of the designs in slices of ``size``, on ``threads`` threads."""
    parts = thread_map(fn, [slice(lo, min(lo + size, n)) for lo in range(0, n, size)],
                       threads)
    return [row for part in parts for row in part]


def _row(coil: Coil, k: int, cs: _Circuits, villari: np.ndarray, approach: np.ndarray,
         peak_emf: float, peak_v: float, wave: Wave) -> dict:
    fig = cs.figures
    noise = float(cs.noise_rms[k])
    return {
        "outer_radius_m": coil.outer_radius,
        "resistance_ohm": float(cs.resistance[k]), "inductance_H": float(cs.inductance[k]),
        "winding_capacitance_F": float(cs.winding_capacitance[k]),
        "resonance_Hz": float(fig.resonance_hz[k]),
        "quality_factor": float(fig.quality_factor[k]),
        "bandwidth_Hz": float(fig.bandwidth_hz[k]), "noise_rms_V": noise,
        "sensitivity_villari_Wb_per_N": float(np.sum(villari)),
        "dLambda_dapproach_Wb_per_m": float(np.sum(approach)),
        "peak_emf_V": peak_emf,
        "peak_voltage_V": peak_v, "snr": peak_v / noise,
        "precompression_N": wave.precompression_N,
        "precompression_max_N": wave.precompression_max_N,
        "wave_speed_change": wave.wave_speed_change,
    }


#: Designs whose eddy-current spectra are formed at once (about 1 MB a design on the main
#: study's 20,250-point FFT; 32 ran 25 % faster than 64 or 128 there, the arrays nearer the
#: cache).
SPECTRUM_CHUNK = 32


@dataclass(frozen=True)
class _ChainSpectra:
    """What every design's eddy-current EMF spectrum shares: the contact rates' spectra and
    the bins' places in :func:`msens.magnetics.frequency_response.interp`.

    ``interp`` reads a solved response in three ways, by bin: below the first nonzero solved
    frequency f1 its low-frequency form; from f1 to the last solved frequency f_n a PCHIP in
    log f; from f_n up the value at f_n. A design's EMF(ω) = −Σ_m S_m(ω) R_m(ω) (m over both
    mechanisms' contacts, R the rates' spectra) is therefore, bin by bin,

    - above f_n (most bins: the read-out's FFT reaches 5 MHz, the solves 200 kHz): the
      product of the design's S_m(f_n) with the shared spectra, one matrix product for all
      designs;
    - on the PCHIP interval k: S_m(u) = Σ_p c_pkm (u − u_k)^(3−p), u = log f, so the EMF is
      the design's coefficients c_pkm times the shared table (u − u_k)^(3−p) R_m(u): again
      one matrix product per interval;
    - below f1 (the DC bin): :func:`msens.magnetics.eddy_readout.emf_spectra` itself.

    Attributes
    ----------
    n : int
        FFT length.
    f : ndarray, shape (n // 2 + 1,)
        Bin frequencies, Hz.
    low, top : int
        Bins [0, low) are below f1, bins [top, n // 2 + 1) at or above f_n.
    rates : ndarray of complex, shape (n // 2 + 1, 2 n_c)
        Spectra of dF_c/dt then dδ_c/dt.
    pieces : tuple of (slice, int, ndarray)
        Per PCHIP interval holding bins: their slice, the interval and the table
        −(u − u_k)^(3−p) R_m, shape (4 · 2 n_c, bins).
    top_rates : ndarray of complex, shape (2 n_c, bins above f_n)
        ``-rates[top:].T``.
    """

    n: int
    f: np.ndarray
    low: int
    top: int
    rates: np.ndarray
    pieces: tuple
    top_rates: np.ndarray


def _chain_spectra(wave: Wave, frequencies: np.ndarray) -> _ChainSpectra:
    t = wave.rates.t
    nt = t.size
    dt = float(t[1] - t[0])
    n = scipy.fft.next_fast_len(math.ceil(PAD * nt), real=True)
    f = np.fft.rfftfreq(n, dt)
    rates = np.concatenate([scipy.fft.rfft(wave.rates.force, n, axis=0),
                            scipy.fft.rfft(wave.rates.approach, n, axis=0)], axis=1)
    freqs = np.asarray(frequencies, float)
    low = int(np.searchsorted(f, freqs[1], side="left"))  # f < f1
    top = max(low, int(np.searchsorted(f, freqs[-1], side="left")))  # f >= f_n
    pieces = []
    if top > low:
        nodes = np.log(freqs[1:])
        u = np.log(f[low:top])
        interval = np.clip(np.searchsorted(nodes, u, side="right") - 1, 0, nodes.size - 2)
        for k in np.unique(interval):
            idx = np.nonzero(interval == k)[0]
            sl = slice(low + int(idx[0]), low + int(idx[-1]) + 1)
            dx = u[idx] - nodes[k]
            power = np.stack([dx**3, dx**2, dx, np.ones_like(dx)])  # (4, bins)
            table = power[:, None, :] * -rates[sl].T[None]  # (4, 2 n_c, bins)
            pieces.append((sl, int(k), table.reshape(-1, idx.size)))
    return _ChainSpectra(n=n, f=f, low=low, top=top, rates=rates, pieces=tuple(pieces),
                         top_rates=np.ascontiguousarray(-rates[top:].T))


#: Singular values of the designs' weighted sensitivities at f_n kept by :func:`_top_basis`,
#: relative to the largest (1e-14: rounding; on the main study's 12,740-design benchmark
#: grid 21 of 60 columns).
TOP_RANK_TOL = 1e-14


@dataclass(frozen=True)
class _TopBasis:
    """The designs' sensitivities at f_n in a basis of few columns.

    Above f_n every design's EMF is a_d · (−R(f)) with a_d = [S_c(f_n), D_c(f_n)] (2 n_c
    values) and R the contact rates' spectra. Weighted by each rate spectrum's norm w, the
    designs' rows a_d W span few dimensions (the coils' linkages of neighbouring contacts
    are smooth functions of the winding): a_d W ≈ (a_d W V) Vᴴ with V the leading right
    singular vectors. Then a_d · R = (a_d W V) · (Vᴴ W⁻¹ R): one product with r ≪ 2 n_c
    rows instead of 2 n_c, exact to the singular values dropped (:data:`TOP_RANK_TOL`).

    Attributes
    ----------
    weights : ndarray of complex, shape (2 n_c, r)
        W V.
    rates : ndarray of complex, shape (r, bins above f_n)
        Vᴴ W⁻¹ (−R).
    """

    weights: np.ndarray
    rates: np.ndarray


def _top_basis(spectra: _ChainSpectra, at_top: np.ndarray) -> _TopBasis:
    """:class:`_TopBasis` of designs whose sensitivities at f_n are ``at_top`` (shape
    (n_d, 2 n_c))."""
    w = np.linalg.norm(spectra.top_rates, axis=1)
    w[w == 0] = 1.0
    _, sv, vh = np.linalg.svd(at_top * w, full_matrices=False)
    r = max(1, int(np.sum(sv > TOP_RANK_TOL * sv[0]))) if sv.size and sv[0] > 0 else 1
    return _TopBasis(weights=np.ascontiguousarray(w[:, None] * vh[:r].conj().T),
                     rates=np.ascontiguousarray((vh[:r] / w[None, :]) @ spectra.top_rates))


def _emf_spectra(spectra: _ChainSpectra, frequencies: np.ndarray, villari: np.ndarray,
                 approach: np.ndarray, top_basis: _TopBasis) -> np.ndarray:
    """EMF(ω) of many designs, shape (n_d, bins): :func:`msens.magnetics.eddy_readout.
    emf_spectra` of their S_c(ω), D_c(ω) (shape (n_d, n_f, n_c) each), by the matrix
    products of :class:`_ChainSpectra` (equal to it to rounding, tests); above f_n through
    ``top_basis`` (:func:`_top_basis` of these or more designs)."""
    freqs = np.asarray(frequencies, float)
    sp = spectra
    n_d = villari.shape[0]
    out = np.empty((n_d, sp.f.size), dtype=complex)
    if sp.low:
        n_c = villari.shape[2]
        out[:, :sp.low] = emf_spectra(
            freqs[:2], np.moveaxis(villari[:, :2], 1, 0), np.moveaxis(approach[:, :2], 1, 0),
            sp.f[:sp.low], sp.rates[:sp.low, :n_c], sp.rates[:sp.low, n_c:]).T
    both = np.moveaxis(np.concatenate([villari, approach], axis=2), 1, 0)  # (n_f, n_d, 2n_c)
    if freqs.size > 2:
        # the PCHIP of interp on the same values, real and imaginary parts side by side (it
        # acts on each column alone: the same coefficients)
        pchip = PchipInterpolator(np.log(freqs[1:]),
                                  np.stack([both[1:].real, both[1:].imag], axis=-1), axis=0)
        top = pchip(np.log(np.minimum(freqs[-1:], freqs[-1])))[0]  # interp's, from f_n up
        at_top = top[..., 0] + 1j * top[..., 1]  # (n_d, 2n_c)
        coef = np.moveaxis(pchip.c[..., 0] + 1j * pchip.c[..., 1], 2, 0)  # (n_d, 4, ., 2n_c)
        for sl, k, table in sp.pieces:
            np.matmul(coef[:, :, k].reshape(n_d, -1), table, out=out[:, sl])
    else:
        at_top = both[1]
    np.matmul(at_top @ top_basis.weights, top_basis.rates, out=out[:, sp.top:])
    return out


def _coil_impedances(spectra: _ChainSpectra, frequencies: np.ndarray,
                     inductance_w: np.ndarray, resistance: np.ndarray) -> np.ndarray:
    """Z = R + jωL(ω) of many designs, shape (n_d, bins): :func:`msens.magnetics.
    frequency_response.coil_impedance` below f_n, its constant-L form from f_n up."""
    sp = spectra
    freqs = np.asarray(frequencies, float)
    # L(ω) as coil_impedance interpolates it: at the bins below f_n, then from f_n up
    ind = interp(freqs, np.asarray(inductance_w).T, np.append(sp.f[:sp.top], freqs[-1])).T
    z = np.empty((ind.shape[0], sp.f.size), dtype=complex)
    w = TWO_PI * sp.f
    np.multiply(1j * w[:sp.top], ind[:, :-1], out=z[:, :sp.top])
    np.multiply(1j * w[sp.top:], ind[:, -1:], out=z[:, sp.top:])
    z += resistance[:, None]
    return z


def _peaks(x: np.ndarray) -> np.ndarray:
    """max |x| along the last axis."""
    return np.maximum(np.max(x, axis=-1), -np.min(x, axis=-1))


def dynamic_design_rows(coils: Sequence[Coil], resistance: np.ndarray, inductance: np.ndarray,
                        frequencies: np.ndarray, villari: np.ndarray, approach: np.ndarray,
                        inductance_w: np.ndarray, wave: Wave,
                        electronics: ElectronicsSpec, threads: int = 1) -> list[dict]:
    """Metrics of coil designs with eddy currents, one dict per design.

    The EMF and the DAQ voltage are those of ``msens run`` with eddy currents
    (:func:`msens.readout.mss.mss_signals`): the contact rates' spectra times the
    complex sensitivities (:func:`msens.magnetics.eddy_readout.emf_spectra`), then the read-out
    circuit with the coil's series impedance Z(ω) = R + jωL(ω)
    (:func:`msens.readout.electronics.coil_transfer_function`), on the run's FFT length
    (:data:`msens.readout.mss.PAD`). Resonance, Q, bandwidth and noise are the static
    circuit's (R, bias-point L), as ``summary.json`` reports them.

    Vectorised over designs: the chain's spectra are formed once and every chunk of designs'
    EMF spectra is a few matrix products with them (:class:`_ChainSpectra`); the inverse FFTs
    run on the whole chunk. The results equal the design-by-design evaluation to rounding
    (``tests/design/test_eddy_batch.py``).

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
    threads : int
        Threads the chunks of designs run on (:func:`msens.parallel.thread_map`).
    """
    sp = _chain_spectra(wave, frequencies)
    villari, approach = np.asarray(villari), np.asarray(approach)
    resistance = np.asarray(resistance, float)
    cs = _circuits(coils, resistance, inductance, electronics)
    inductance_w = np.asarray(inductance_w)
    basis = _top_basis(sp, np.concatenate([villari[:, -1], approach[:, -1]], axis=1))

    def chunk(sl: slice) -> list[dict]:
        return _dynamic_chunk(sl, sp, basis, coils, frequencies, villari, approach,
                              inductance_w, cs, wave)

    return _chunked(chunk, len(coils), SPECTRUM_CHUNK, threads)


def _dynamic_chunk(sl: slice, sp: _ChainSpectra, basis: _TopBasis, coils: Sequence[Coil],
                   frequencies: np.ndarray,
                   villari: np.ndarray, approach: np.ndarray, inductance_w: np.ndarray,
                   cs: _Circuits, wave: Wave) -> list[dict]:
    """The rows of designs ``sl`` of :func:`dynamic_design_rows`."""
    nt = wave.rates.t.size
    e_hat = _emf_spectra(sp, frequencies, villari[sl], approach[sl], basis)
    z = _coil_impedances(sp, frequencies, inductance_w[sl], cs.resistance[sl])
    h = coil_transfer_functions(cs.load, cs.winding_capacitance[sl], sp.f, z, e_hat)
    peak_e = _peaks(scipy.fft.irfft(e_hat, sp.n, axis=1)[:, :nt])
    peak_v = _peaks(scipy.fft.irfft(h, sp.n, axis=1)[:, :nt])
    return [_row(coils[k], k, cs, villari[k, 0].real, approach[k, 0].real, float(peak_e[j]),
                 float(peak_v[j]), wave) for j, k in enumerate(range(sl.start, sl.stop))]


__all__ = ["DECAY_TIMES", "EMF_CHUNK", "SPECTRUM_CHUNK", "Wave", "design_rows",
           "dynamic_design_rows"]
