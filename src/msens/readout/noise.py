"""Noise of the read-out circuit (:mod:`msens.readout.electronics`) at the DAQ.

Thermal (Johnson) noise of the coil's, the cable's and the input's resistances, the DAQ's
input noise and its quantisation (:class:`NoiseModel`): exact sampled realisations of the
continuous-time process (:func:`add_readout_noise`), the power spectral density and the RMS
in a band.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate, linalg

from msens.errors import InputError, require
from msens.params.units import K_B
from msens.readout.electronics import (
    ReadoutCircuit,
    _admittances,
    _linear_recursion,
    _transfer,
    resonance,
    state_space,
)


def _noise_transfers(circuit: ReadoutCircuit, f: np.ndarray,
                     coil_impedance: np.ndarray | None = None):
    """V_daq per unit source of the coil's, the cable's and R_in's thermal noise.

    Returns (H_coil [V/V], H_cable [V/V], Z_out [V/A]): the coil noise is a voltage source in
    series with R (same path as the EMF), the cable's in series with R_c, and R_in's a
    current source across R_in. ``coil_impedance`` (Ω, shape of f) replaces R + sL.
    """
    s, z_s, y_b = _admittances(circuit, f)
    if coil_impedance is not None:
        z_s = np.asarray(coil_impedance, dtype=complex)
    r_c = circuit.cable_resistance
    h_coil = _transfer(circuit, s, z_s, y_b)
    y_a = 1.0 + z_s * s * circuit.winding_capacitance      # Z_A = Z_s / y_a
    h_cable = y_a / (y_a + y_b * (z_s + r_c * y_a))        # 1 / (1 + Y_B (Z_A + R_c))
    z_out = 1.0 / (y_b + y_a / (r_c * y_a + z_s))          # node B to ground
    return h_coil, h_cable, z_out


def _as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(0 if rng is None else rng)


@dataclass(frozen=True)
class NoiseModel:
    """Noise at the DAQ.

    Attributes
    ----------
    temperature_K : float
        Temperature of all resistors (coil, cable, R_in) for their Johnson noise, K.
        0 switches thermal noise off.
    adc_bits : int or None
        ADC resolution; None = no quantisation.
    adc_range_V : float or None
        ADC full-scale span (peak to peak), V; codes −2^(b−1) … 2^(b−1)−1 of
        LSB = span / 2^b, values outside are clipped. Needed with ``adc_bits``.
    input_noise_V_per_rtHz : float
        Input-referred DAQ noise density, V/√Hz, white over the Nyquist band
        (per-sample variance e_n² · fs/2).
    """

    temperature_K: float = 293.15
    adc_bits: int | None = None
    adc_range_V: float | None = None
    input_noise_V_per_rtHz: float = 0.0

    def __post_init__(self) -> None:
        require(self.temperature_K >= 0, f"noise temperature must be >= 0 K, got "
                f"{self.temperature_K}")
        require((self.adc_bits is None) == (self.adc_range_V is None),
                "give both adc_bits and adc_range_V, or neither")
        if self.adc_bits is not None:
            require(isinstance(self.adc_bits, int) and 1 <= self.adc_bits <= 32,
                    f"adc_bits must be an integer 1..32, got {self.adc_bits!r}")
            require(self.adc_range_V > 0, f"adc_range_V must be > 0 V, got "
                    f"{self.adc_range_V}")
        require(self.input_noise_V_per_rtHz >= 0,
                f"input_noise_V_per_rtHz must be >= 0, got {self.input_noise_V_per_rtHz}")

    @property
    def lsb(self) -> float | None:
        """ADC step, V (None without quantisation)."""
        if self.adc_bits is None:
            return None
        return self.adc_range_V / 2**self.adc_bits


def _thermal_intensity(circuit: ReadoutCircuit, temperature: float) -> np.ndarray:
    """Two-sided white-noise intensities of the 3 state-space inputs (2kTR, 2kTR_c, 2kT/R_in)."""
    return 2.0 * K_B * temperature * np.array(
        [circuit.resistance, circuit.cable_resistance, circuit.input_conductance])


def thermal_covariance(circuit: ReadoutCircuit, temperature_K: float) -> np.ndarray:
    """Stationary state covariance P of the thermal noise: A P + P Aᵀ + B S Bᵀ = 0."""
    a, b, _ = state_space(circuit)
    q = b @ np.diag(_thermal_intensity(circuit, temperature_K)) @ b.T
    p = linalg.solve_continuous_lyapunov(a, -q)
    return 0.5 * (p + p.T)


def _thermal_realisation(circuit: ReadoutCircuit, temperature: float, n: int, dt: float,
                         rng: np.random.Generator) -> np.ndarray:
    """Exact samples (spacing dt) of the stationary thermal noise at the DAQ, V, shape (n,)."""
    a, _, c = state_space(circuit)
    p = thermal_covariance(circuit, temperature)
    phi = linalg.expm(a * dt)
    q = p - phi @ p @ phi.T                     # exact one-step covariance of a stationary AR(1)
    w, v = linalg.eigh(0.5 * (q + q.T))
    q_half = v * np.sqrt(np.clip(w, 0.0, None))
    w0, v0 = linalg.eigh(p)
    x0 = (v0 * np.sqrt(np.clip(w0, 0.0, None))) @ rng.standard_normal(len(c))
    drive = rng.standard_normal((n - 1, len(c))) @ q_half.T
    return _linear_recursion(phi, x0, np.ascontiguousarray(drive)) @ c


def _quantise(v: np.ndarray, noise: NoiseModel) -> np.ndarray:
    lsb = noise.lsb
    half = 2 ** (noise.adc_bits - 1)
    return lsb * np.clip(np.round(v / lsb), -half, half - 1)


def add_readout_noise(v: np.ndarray, circuit: ReadoutCircuit, noise: NoiseModel,
                      sample_rate: float, *, rng: np.random.Generator | int | None = None,
                      coil_impedance: Callable[[np.ndarray], np.ndarray] | None = None
                      ) -> np.ndarray:
    """A DAQ record with the read-out's noise added, V, shape (m,).

    In order: the circuit-shaped Johnson noise of the coil, R_c and R_in; white DAQ input
    noise of variance e_n² fs/2 per sample; ADC quantisation and clipping. The Johnson noise
    is an exact sampled realisation of the state-space model when the coil is R + sL. With a
    frequency-dependent coil impedance Z(f) (eddy currents) the coil's noise EMF has the
    one-sided PSD 4kT Re Z(f) (fluctuation–dissipation), and the noise is synthesised in the
    frequency domain from :func:`thermal_noise_psd` on twice the record's length (so that
    the wrap-around of the FFT does not correlate its ends).

    Parameters
    ----------
    v : ndarray, shape (m,)
        Noise-free DAQ voltage sampled at ``sample_rate``, V.
    circuit : ReadoutCircuit
    noise : NoiseModel
    sample_rate : float
        Hz.
    rng : numpy.random.Generator or int, optional
        None = seed 0.
    coil_impedance : callable, optional
        f (Hz, shape (k,)) -> Z (Ω, complex, shape (k,)), e.g.
        :meth:`msens.magnetics.frequency_response.FrequencyResponse.impedance_at`.
    """
    v = np.asarray(v, dtype=float)
    gen = _as_rng(rng)
    dt = 1.0 / sample_rate
    if noise.temperature_K > 0:
        if coil_impedance is None:
            v = v + _thermal_realisation(circuit, noise.temperature_K, v.size, dt, gen)
        else:
            v = v + _spectral_realisation(circuit, noise.temperature_K, v.size, sample_rate,
                                          gen, coil_impedance)
    if noise.input_noise_V_per_rtHz > 0:
        sigma = noise.input_noise_V_per_rtHz * math.sqrt(sample_rate / 2.0)
        v = v + sigma * gen.standard_normal(v.size)
    if noise.adc_bits is not None:
        v = _quantise(v, noise)
    return v


def _spectral_realisation(circuit: ReadoutCircuit, temperature: float, n: int,
                          sample_rate: float, rng: np.random.Generator,
                          coil_impedance: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """Gaussian samples of the Johnson noise at the DAQ with PSD S(f), V, shape (n,).

    E|X_k|² = n fs S(f_k) / 2 for the real FFT of n samples, so that the variance per sample
    is ∫_0^{fs/2} S df (S beyond fs/2 is negligible for a read-out that rolls off below it).
    """
    from scipy.fft import irfft, next_fast_len, rfftfreq

    size = next_fast_len(2 * n, real=True)
    f = rfftfreq(size, 1.0 / sample_rate)
    psd = thermal_noise_psd(circuit, temperature, f, coil_impedance=coil_impedance(f))
    amp = np.sqrt(psd * size * sample_rate / 2.0)
    x = rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)
    x *= amp / math.sqrt(2.0)
    x[0] = amp[0] * rng.standard_normal()
    if size % 2 == 0:
        x[-1] = amp[-1] * rng.standard_normal()
    return irfft(x, size)[:n]


def thermal_noise_psd(circuit: ReadoutCircuit, temperature_K: float,
                      f: ArrayLike, *, coil_impedance: ArrayLike | None = None) -> np.ndarray:
    """One-sided PSD of the Johnson noise at the DAQ, V²/Hz, shape (n,).

    S(f) = 4kT (Re Z |H|² + R_c |H_c|² + |Z_out|² / R_in), Z the coil's series impedance:
    R + sL by default, or ``coil_impedance`` (Ω, complex, shape (n,)) — e.g. with eddy-current
    losses, whose Re Z > R is the coil's extra noise.
    """
    f = np.asarray(f, dtype=float)
    if coil_impedance is not None:
        coil_impedance = np.asarray(coil_impedance, dtype=complex)
        require(coil_impedance.shape == f.shape,
                f"coil_impedance must have the shape of f {f.shape}, got "
                f"{coil_impedance.shape}")
    h_coil, h_cable, z_out = _noise_transfers(circuit, f, coil_impedance)
    r_coil = circuit.resistance if coil_impedance is None else coil_impedance.real
    return 4.0 * K_B * temperature_K * (
        r_coil * np.abs(h_coil) ** 2
        + circuit.cable_resistance * np.abs(h_cable) ** 2
        + circuit.input_conductance * np.abs(z_out) ** 2)


def _band(bandwidth: float | tuple[float, float]) -> tuple[float, float]:
    if isinstance(bandwidth, tuple):
        lo, hi = (float(x) for x in bandwidth)
    else:
        lo, hi = 0.0, float(bandwidth)
    require(0 <= lo < hi and math.isfinite(hi),
            f"bandwidth must be f_max > 0 or (f_lo, f_hi) with 0 <= f_lo < f_hi finite, got "
            f"{bandwidth!r}")
    return lo, hi


def _integrate_psd(circuit: ReadoutCircuit, temperature: float, lo: float, hi: float) -> float:
    """∫_lo^hi S(f) df with breakpoints around the resonance peak."""
    try:
        f0, q = resonance(circuit)
        width = f0 / max(q, 0.5)
        marks = [f0 - 4 * width, f0 - width, f0, f0 + width, f0 + 4 * width]
        marks += list(np.geomspace(f0 * 1e-3, f0 * 1e3, 13))
    except InputError:              # no state space (L = 0 or no capacitance): smooth PSD
        marks = []
    edges = sorted({lo, hi, *(m for m in marks if lo < m < hi)})
    total = 0.0
    for f1, f2 in itertools.pairwise(edges):
        val, _ = integrate.quad(lambda f: float(thermal_noise_psd(circuit, temperature,
                                                                  [f])[0]),
                                f1, f2, limit=200, epsabs=0.0, epsrel=1e-10)
        total += val
    return total


def daq_capacitance(circuit: ReadoutCircuit) -> float:
    """Capacitance of the DAQ node, F: all of it (C_w + C_B) with R_c = 0, else C_B."""
    if circuit.cable_resistance == 0.0:
        return circuit.total_capacitance
    return circuit.load_capacitance


def _has_daq_noise(noise: NoiseModel, sample_rate: float | None) -> bool:
    has = noise.input_noise_V_per_rtHz > 0 or noise.adc_bits is not None
    if has:
        require(sample_rate is not None and sample_rate > 0,
                "noise_rms needs sample_rate (Hz) for DAQ input or quantisation noise")
    return has


def total_noise_rms(capacitance: ArrayLike, noise: NoiseModel,
                    sample_rate: float | None = None) -> np.ndarray:
    """Per-sample RMS noise at the DAQ over all frequencies, V, of read-outs whose DAQ node
    has ``capacitance`` (F, any shape; :func:`daq_capacitance`): vectorised, e.g. over a
    coil sweep's circuits.

    Thermal part: every resistor is at ``noise.temperature_K``, so the circuit is in
    thermal equilibrium and the energy ½ C v² of the DAQ node's capacitor holds ½ kT
    (equipartition; the stationary covariance of :func:`thermal_covariance` is
    kT · diag(1/L, 1/C…), checked in the tests): ⟨v²⟩ = kT / C, whatever R, L and R_in.
    DAQ part: the input noise density over the Nyquist band, e_n² fs / 2, and the
    quantisation noise LSB² / 12.
    """
    c = np.asarray(capacitance, dtype=float)
    var = np.zeros(c.shape)
    if noise.temperature_K > 0:
        require(bool(np.all(c > 0)), "the read-out's thermal noise needs a DAQ node "
                "capacitance > 0 F (winding + cable + input)")
        var = K_B * noise.temperature_K / c
    if _has_daq_noise(noise, sample_rate):
        var = var + noise.input_noise_V_per_rtHz**2 * sample_rate / 2.0
        if noise.lsb is not None:
            var = var + noise.lsb**2 / 12.0
    return np.sqrt(var)


def noise_rms(circuit: ReadoutCircuit, noise: NoiseModel,
              bandwidth: float | tuple[float, float] | None = None, *,
              sample_rate: float | None = None) -> float:
    """RMS noise voltage at the DAQ, V.

    Parameters
    ----------
    circuit : ReadoutCircuit
    noise : NoiseModel
    bandwidth : float or (float, float), optional
        Band 0…f_max or f_lo…f_hi, Hz. None: all frequencies, i.e. the per-sample RMS of
        the recorded noise (:func:`total_noise_rms`) — thermal part kT / C by
        equipartition, DAQ input noise over the Nyquist band, full quantisation noise.
    sample_rate : float, optional
        DAQ rate, Hz; needed for the DAQ-noise and quantisation parts when they apply
        (quantisation noise LSB²/12 is spread evenly over 0…fs/2).
    """
    if bandwidth is None:
        return float(total_noise_rms(daq_capacitance(circuit), noise, sample_rate))
    var = 0.0
    has_daq_noise = _has_daq_noise(noise, sample_rate)
    lo, hi = _band(bandwidth)
    if noise.temperature_K > 0:
        var += _integrate_psd(circuit, noise.temperature_K, lo, hi)
    if has_daq_noise:
        nyquist = sample_rate / 2.0
        width = max(0.0, min(hi, nyquist) - min(lo, nyquist))
        var += noise.input_noise_V_per_rtHz**2 * width
        if noise.lsb is not None:
            var += noise.lsb**2 / 12.0 * width / nyquist
    return math.sqrt(var)
