"""Read-out circuit of the pick-up coil: from the induced EMF to the voltage the DAQ records.

Circuit (one node per capacitor)::

    EMF ─ R ─ L ─┬─ R_c ─┬──────┬─────┐
                 C_w     C_B   R_in   DAQ       C_B = C_cable + C_in
                 ⏚       ⏚      ⏚

The EMF source is in series with the coil's copper resistance R and inductance L; the
winding's self-capacitance C_w sits across the coil terminals (node A); a cable with lumped
series resistance R_c (default 0) carries the signal to the DAQ (node B), where the cable
capacitance and the DAQ input (R_in ∥ C_in) load it. With R_c = 0 the two nodes merge and the
circuit is a second-order low-pass; with R_c > 0 it is third order.

Sampling: the DAQ is an ideal sampler at ``sample_rate`` — no anti-alias filter beyond the
circuit itself and the DAQ's input capacitance, which is how a wide-band digitiser running at
10 MHz behaves for a signal band of ~100 kHz. The EMF record is read as piecewise linear
between its samples (first-order hold) and the circuit's response to it is computed exactly
(matrix exponential) at the DAQ's sampling instants; noise is an exact sampled realisation of
the continuous-time process, so its aliasing is included.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate, linalg, optimize

from msens.errors import InputError, require
from msens.params.units import K_B

#: Capacitance of 1 m of RG-58 coaxial cable, F (about 100 pF/m; e.g. Belden 8240:
#: 30.8 pF/ft = 101 pF/m).
RG58_CAPACITANCE_PER_M = 100e-12
#: A typical oscilloscope / digitiser high-impedance input: 1 MΩ ∥ 20 pF.
TYPICAL_INPUT_RESISTANCE = 1e6
TYPICAL_INPUT_CAPACITANCE = 20e-12


@dataclass(frozen=True)
class ReadoutCircuit:
    """Lumped coil–cable–DAQ circuit (SI units).

    Attributes
    ----------
    resistance : float
        Coil copper resistance R, Ω (> 0).
    inductance : float
        Coil inductance L, H (>= 0; > 0 for time-domain use).
    winding_capacitance : float
        Winding self-capacitance C_w across the coil terminals, F.
    cable_capacitance : float
        Lumped cable capacitance, F (placed at the DAQ end).
    input_resistance : float
        DAQ input resistance R_in, Ω (``math.inf`` allowed).
    input_capacitance : float
        DAQ input capacitance C_in, F.
    cable_resistance : float
        Lumped series resistance of the cable R_c, Ω (default 0).
    """

    resistance: float
    inductance: float
    winding_capacitance: float
    cable_capacitance: float
    input_resistance: float
    input_capacitance: float
    cable_resistance: float = 0.0

    def __post_init__(self) -> None:
        require(math.isfinite(self.resistance) and self.resistance > 0,
                f"coil resistance must be a finite value > 0 Ω, got {self.resistance}")
        require(math.isfinite(self.inductance) and self.inductance >= 0,
                f"coil inductance must be >= 0 H, got {self.inductance}")
        for name in ("winding_capacitance", "cable_capacitance", "input_capacitance",
                     "cable_resistance"):
            value = getattr(self, name)
            require(math.isfinite(value) and value >= 0, f"{name} must be >= 0, got {value}")
        require(self.input_resistance > 0,
                f"input_resistance must be > 0 Ω (inf allowed), got {self.input_resistance}")

    @property
    def load_capacitance(self) -> float:
        """C_B = cable + DAQ input capacitance, F."""
        return self.cable_capacitance + self.input_capacitance

    @property
    def total_capacitance(self) -> float:
        """All capacitance across the coil when R_c = 0, F."""
        return self.winding_capacitance + self.load_capacitance


def readout_circuit(resistance: float, inductance: float, winding_capacitance: float, *,
                    cable_length_m: float = 1.0,
                    cable_capacitance_per_m: float = RG58_CAPACITANCE_PER_M,
                    input_resistance: float = TYPICAL_INPUT_RESISTANCE,
                    input_capacitance: float = TYPICAL_INPUT_CAPACITANCE,
                    cable_resistance: float = 0.0) -> ReadoutCircuit:
    """A :class:`ReadoutCircuit` with the typical cable (1 m RG-58) and DAQ (1 MΩ ∥ 20 pF)."""
    require(cable_length_m >= 0, f"cable length must be >= 0 m, got {cable_length_m}")
    return ReadoutCircuit(resistance, inductance, winding_capacitance,
                          cable_length_m * cable_capacitance_per_m, input_resistance,
                          input_capacitance, cable_resistance)


def _conductance(resistance: float) -> float:
    return 0.0 if math.isinf(resistance) else 1.0 / resistance


# --------------------------------------------------------------------------- frequency domain

def _admittances(circuit: ReadoutCircuit, f: np.ndarray):
    """s, series coil impedance Z_s = R + sL, load admittance Y_B = 1/R_in + s C_B."""
    s = 2j * np.pi * f
    z_s = circuit.resistance + s * circuit.inductance
    y_b = _conductance(circuit.input_resistance) + s * circuit.load_capacitance
    return s, z_s, y_b


def transfer_function(circuit: ReadoutCircuit, f: ArrayLike) -> np.ndarray:
    """H(j2πf) = V_daq / EMF.

    H = 1 / ((1 + Z_s Y_p)(1 + R_c Y_B)) with Z_s = R + sL, Y_B = 1/R_in + s C_B and
    Y_p = s C_w + Y_B / (1 + R_c Y_B) the admittance across the coil terminals.

    Parameters
    ----------
    circuit : ReadoutCircuit
    f : array_like, shape (n,)
        Frequencies, Hz (>= 0).

    Returns
    -------
    ndarray of complex, shape (n,)
    """
    f = np.asarray(f, dtype=float)
    s, z_s, y_b = _admittances(circuit, f)
    return _transfer(circuit, s, z_s, y_b)


def _transfer(circuit: ReadoutCircuit, s: np.ndarray, z_s: np.ndarray,
              y_b: np.ndarray) -> np.ndarray:
    """1 / ((1 + Z_s Y_p)(1 + R_c Y_B)) for a series coil impedance Z_s (any model)."""
    div = 1.0 + circuit.cable_resistance * y_b
    y_p = s * circuit.winding_capacitance + y_b / div
    return 1.0 / ((1.0 + z_s * y_p) * div)


def coil_transfer_function(circuit: ReadoutCircuit, f: ArrayLike,
                           coil_impedance: ArrayLike) -> np.ndarray:
    """H(j2πf) = V_daq / EMF with an arbitrary series coil impedance Z(f).

    As :func:`transfer_function` with Z_s = ``coil_impedance`` in place of R + sL (e.g. the
    eddy-current impedance R_dc + jωΛ(ω)/I of :mod:`msens.magnetics.dynamic`); the
    circuit's own ``resistance`` and ``inductance`` are not used. The winding capacitance,
    cable and DAQ input are the circuit's.

    Parameters
    ----------
    circuit : ReadoutCircuit
    f : array_like, shape (n,)
        Frequencies, Hz (>= 0).
    coil_impedance : array_like of complex, shape (n,)
        Z_s at ``f``, Ω.

    Returns
    -------
    ndarray of complex, shape (n,)
    """
    f = np.asarray(f, dtype=float)
    z = np.asarray(coil_impedance, dtype=complex)
    require(z.shape == f.shape, f"coil_impedance must have the shape of f {f.shape}, got "
            f"{z.shape}")
    s, _, y_b = _admittances(circuit, f)
    return _transfer(circuit, s, z, y_b)


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


# --------------------------------------------------------------------------- state space

def state_space(circuit: ReadoutCircuit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Continuous state-space model ẋ = A x + B u, v_daq = C x.

    States: coil current i_L and the capacitor voltages (v_A when R_c > 0, then v_B).
    Inputs u = [EMF (+ coil thermal noise), cable thermal noise, R_in noise current].

    Returns
    -------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, 3)
    C : ndarray, shape (n,)
    """
    c = circuit
    require(c.inductance > 0, "the circuit's state-space model (time domain, resonance, "
            "bandwidth, total noise) needs coil inductance > 0 H")
    g_in = _conductance(c.input_resistance)
    inv_l = 1.0 / c.inductance
    if c.cable_resistance == 0.0:
        require(c.total_capacitance > 0,
                "the circuit's state-space model needs winding + cable + input capacitance "
                "> 0 F")
        inv_c = 1.0 / c.total_capacitance
        a = np.array([[-c.resistance * inv_l, -inv_l],
                      [inv_c, -g_in * inv_c]])
        b = np.array([[inv_l, 0.0, 0.0],
                      [0.0, 0.0, inv_c]])
        return a, b, np.array([0.0, 1.0])
    require(c.winding_capacitance > 0 and c.load_capacitance > 0,
            "with cable_resistance > 0 both the winding capacitance and cable + input "
            "capacitance must be > 0 F")
    g_c = 1.0 / c.cable_resistance
    inv_a = 1.0 / c.winding_capacitance
    inv_b = 1.0 / c.load_capacitance
    a = np.array([[-c.resistance * inv_l, -inv_l, 0.0],
                  [inv_a, -g_c * inv_a, g_c * inv_a],
                  [0.0, g_c * inv_b, -(g_c + g_in) * inv_b]])
    b = np.array([[inv_l, 0.0, 0.0],
                  [0.0, -g_c * inv_a, 0.0],
                  [0.0, g_c * inv_b, inv_b]])
    return a, b, np.array([0.0, 0.0, 1.0])


def poles(circuit: ReadoutCircuit) -> np.ndarray:
    """Poles of H(s), rad/s, sorted by magnitude (complex, shape (2,) or (3,))."""
    p = linalg.eigvals(state_space(circuit)[0])
    return p[np.argsort(np.abs(p))]


def resonance(circuit: ReadoutCircuit) -> tuple[float, float]:
    """Self-resonance frequency f0 (Hz) and quality factor Q of the coil read-out.

    From the two poles of smallest magnitude p1, p2 (the coil–capacitance pair; with
    R_c > 0 the third pole is the fast R_c pole): ω0 = √(p1 p2), Q = ω0 / (−(p1 + p2)).
    For a complex pair −σ ± jω_d this is ω0 = |p|, Q = |p|/(2σ); for R_c = 0,
    ω0² = (1 + R/R_in)/(L C) and Q = ω0 L C / (R C + L/R_in).
    """
    p = poles(circuit)[:2]
    omega0 = math.sqrt(abs((p[0] * p[1]).real))
    return omega0 / (2.0 * math.pi), omega0 / float(-(p[0] + p[1]).real)


def bandwidth(circuit: ReadoutCircuit) -> float:
    """−3 dB bandwidth, Hz: the lowest f at which |H(f)| falls to |H(0)|/√2.

    Above any resonance peak: the peak itself (|H| > |H(0)|) is inside the band.
    """
    f0, _ = resonance(circuit)
    target = abs(transfer_function(circuit, [0.0])[0]) / math.sqrt(2.0)
    grid = np.geomspace(f0 * 1e-6, f0 * 1e6, 4001)
    below = np.nonzero(np.abs(transfer_function(circuit, grid)) < target)[0]
    if below.size == 0:
        raise InputError("circuit has no -3 dB point below 1e6 × its resonance frequency")
    k = int(below[0])
    if k == 0:
        return float(grid[0])

    def excess(f: float) -> float:
        return abs(transfer_function(circuit, [f])[0]) - target

    return float(optimize.brentq(excess, grid[k - 1], grid[k], xtol=1e-12 * grid[k],
                                 rtol=1e-14))


# --------------------------------------------------------------------------- time domain

def _foh_matrices(a: np.ndarray, b: np.ndarray, tau: float):
    """Exact step of ẋ = Ax + Bu over τ with u(t) = u0 + t·du (first-order hold).

    Returns Φ, G0, G1 with x(τ) = Φ x(0) + G0 u0 + G1 du.
    """
    n, m = b.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = a
    big[:n, n:n + m] = b
    big[n:n + m, n + m:] = np.eye(m)
    e = linalg.expm(big * tau)
    return e[:n, :n], e[:n, n:n + m], e[:n, n + m:]


@numba.njit(cache=True)
def _linear_recursion(phi, x0, drive):  # pragma: no cover - compiled
    """x[0] = x0, x[k+1] = Φ x[k] + drive[k]; returns x, shape (K+1, n)."""
    k_steps, n = drive.shape
    x = np.empty((k_steps + 1, n))
    x[0] = x0
    for k in range(k_steps):
        for i in range(n):
            acc = drive[k, i]
            for j in range(n):
                acc += phi[i, j] * x[k, j]
            x[k + 1, i] = acc
    return x


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
        [circuit.resistance, circuit.cable_resistance, _conductance(circuit.input_resistance)])


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


def daq_voltage(circuit: ReadoutCircuit, t: ArrayLike, emf: ArrayLike, sample_rate: float,
                *, noise: NoiseModel | None = None,
                rng: np.random.Generator | int | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
    """Voltage the DAQ records for an EMF record.

    The EMF is taken as piecewise linear between its samples; before ``t[0]`` it is held at
    ``emf[0]`` with the circuit in DC steady state. The response is computed exactly
    (first-order-hold matrix exponentials) on the EMF grid and, by partial steps, at the
    DAQ instants ``t[0] + k / sample_rate`` (k = 0, 1, … while ≤ t[-1]): an ideal sampler,
    no anti-alias filter beyond the circuit (module notes).

    Noise (if ``noise`` is given): an exact sampled realisation of the circuit-shaped
    Johnson noise of R, R_c and R_in; white DAQ input noise of variance e_n² fs/2 per
    sample; then ADC quantisation and clipping.

    Parameters
    ----------
    circuit : ReadoutCircuit
    t : array_like, shape (n,)
        Uniformly spaced times of the EMF record, s (n >= 2).
    emf : array_like, shape (n,)
        Induced EMF, V.
    sample_rate : float
        DAQ sampling rate, Hz (paper: 10 MHz).
    noise : NoiseModel, optional
    rng : numpy.random.Generator or int, optional
        Generator or seed for the noise; None = seed 0 (reproducible by default: pass
        different seeds for independent realisations).

    Returns
    -------
    t_daq : ndarray, shape (m,)
        Sampling instants, s.
    v_daq : ndarray, shape (m,)
        Voltage at the DAQ, V.
    """
    t = np.asarray(t, dtype=float)
    emf = np.asarray(emf, dtype=float)
    require(t.ndim == 1 and t.shape == emf.shape and t.size >= 2,
            f"t and emf must be 1-D arrays of equal length >= 2, got shapes {t.shape} and "
            f"{emf.shape}")
    require(bool(np.all(np.isfinite(t)) and np.all(np.isfinite(emf))),
            "t and emf must be finite")
    dt = (t[-1] - t[0]) / (t.size - 1)
    require(dt > 0 and bool(np.allclose(np.diff(t), dt, rtol=1e-6, atol=0.0)),
            "EMF times t must be increasing and uniformly spaced")
    require(math.isfinite(sample_rate) and sample_rate > 0,
            f"sample_rate must be > 0 Hz, got {sample_rate}")

    a, b, c = state_space(circuit)
    b_emf = b[:, :1]
    slope = np.diff(emf) / dt
    phi, g0, g1 = _foh_matrices(a, b_emf, dt)
    drive = np.outer(emf[:-1], g0[:, 0]) + np.outer(slope, g1[:, 0])
    x0 = -linalg.solve(a, b_emf[:, 0] * emf[0])
    x = _linear_recursion(phi, x0, np.ascontiguousarray(drive))

    n_daq = math.floor((t[-1] - t[0]) * sample_rate * (1 + 1e-12)) + 1
    t_daq = t[0] + np.arange(n_daq) / sample_rate
    pos = (t_daq - t[0]) / dt
    j = np.minimum(np.floor(pos + 1e-9).astype(int), t.size - 2)
    frac = np.clip(pos - j, 0.0, 1.0)
    key = np.round(frac * 1e9).astype(np.int64)    # partial steps equal to 1e-9 dt share Φ
    v = np.empty(n_daq)
    for k in np.unique(key):
        sel = key == k
        jj = j[sel]
        if k == 0:
            v[sel] = x[jj] @ c
            continue
        p_tau, h0, h1 = _foh_matrices(a, b_emf, frac[sel][0] * dt)
        xs = x[jj] @ p_tau.T + np.outer(emf[jj], h0[:, 0]) + np.outer(slope[jj], h1[:, 0])
        v[sel] = xs @ c

    if noise is not None:
        v = add_readout_noise(v, circuit, noise, sample_rate, rng=rng)
    return t_daq, v


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
        :meth:`msens.magnetics.dynamic.FrequencyResponse.impedance_at`.
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


# --------------------------------------------------------------------------- noise levels

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
        + _conductance(circuit.input_resistance) * np.abs(z_out) ** 2)


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
        the recorded noise — thermal part from the stationary covariance (Lyapunov), DAQ
        input noise over the Nyquist band, full quantisation noise.
    sample_rate : float, optional
        DAQ rate, Hz; needed for the DAQ-noise and quantisation parts when they apply
        (quantisation noise LSB²/12 is spread evenly over 0…fs/2).
    """
    var = 0.0
    has_daq_noise = noise.input_noise_V_per_rtHz > 0 or noise.adc_bits is not None
    if has_daq_noise:
        require(sample_rate is not None and sample_rate > 0,
                "noise_rms needs sample_rate (Hz) for DAQ input or quantisation noise")
    if bandwidth is None:
        if noise.temperature_K > 0:
            _, _, c = state_space(circuit)
            var += float(c @ thermal_covariance(circuit, noise.temperature_K) @ c)
        if has_daq_noise:
            var += noise.input_noise_V_per_rtHz**2 * sample_rate / 2.0
            if noise.lsb is not None:
                var += noise.lsb**2 / 12.0
        return math.sqrt(var)
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
