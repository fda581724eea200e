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

This module holds the circuit, its transfer functions, state space, poles and bandwidth;
the sampled DAQ record is in :mod:`msens.readout.daq`, the circuit's noise in
:mod:`msens.readout.noise`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike
from scipy import linalg, optimize

from msens import numba_cache_file  # noqa: F401 (user cache folder; one file per variant)
from msens.errors import InputError, require

#: Capacitance of 1 m of RG-58 coaxial cable, F (about 100 pF/m; e.g. Belden 8240:
#: 30.8 pF/ft = 101 pF/m).
RG58_CAPACITANCE_PER_M = 100e-12

#: A typical oscilloscope / digitiser high-impedance input: 1 MΩ ∥ 20 pF.
TYPICAL_INPUT_RESISTANCE = 1e6

TYPICAL_INPUT_CAPACITANCE = 20e-12


@dataclass(frozen=True)
class ElectronicsSpec:
    """Settings of a coil's read-out rig, as a study's ``[electronics]`` gives them.

    Capacitances in F, resistance in Ohm, rate in Hz. Defaults: 1 m of RG-58 coaxial cable
    into a 1 MOhm || 20 pF DAQ input sampled at the paper's 10 MHz; noise off unless asked
    for. :func:`msens.readout.mss.readout` maps them onto a :class:`ReadoutCircuit`.

    Attributes
    ----------
    cable_capacitance_f : float
        Lumped capacitance of the cable at the DAQ end, F (RG-58: about 100 pF per metre).
    input_resistance_ohm : float
        DAQ input resistance, Ω.
    input_capacitance_f : float
        DAQ input capacitance, F.
    sample_rate_hz : float
        DAQ sampling rate of the coil's voltage, Hz.
    johnson_noise : bool
        Add the coil's thermal (Johnson) noise, 4kT Re Z per hertz.
    temperature_k : float
        Temperature of the coil for its thermal noise, K.
    adc_bits : int or None
        Resolution of the DAQ's converter, given with ``adc_range_V`` (0 or absent: no
        quantisation). Unit: bits.
    adc_range_v : float or None
        Full-scale range of the DAQ's converter, V (given with ``adc_bits``).
    input_noise_v_per_rthz : float
        White voltage noise density of the DAQ input, V/√Hz.
    seed : int
        Seed of the noise generator, so that a noisy record is reproducible. Unit: 1.
    """

    cable_capacitance_f: float = RG58_CAPACITANCE_PER_M * 1.0
    input_resistance_ohm: float = TYPICAL_INPUT_RESISTANCE
    input_capacitance_f: float = TYPICAL_INPUT_CAPACITANCE
    sample_rate_hz: float = 10e6
    johnson_noise: bool = False
    temperature_k: float = 293.15
    adc_bits: int | None = None
    adc_range_v: float | None = None
    input_noise_v_per_rthz: float = 0.0
    seed: int = 0


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
    def input_conductance(self) -> float:
        """G = 1 / R_in, S (0 for an open input)."""
        return _conductance(self.input_resistance)

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


def _admittances(circuit: ReadoutCircuit, f: np.ndarray):
    """s, series coil impedance Z_s = R + sL, load admittance Y_B = 1/R_in + s C_B."""
    s = 2j * np.pi * f
    z_s = circuit.resistance + s * circuit.inductance
    y_b = circuit.input_conductance + s * circuit.load_capacitance
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


def coil_transfer_functions(load: ReadoutCircuit, winding_capacitance: ArrayLike, f: ArrayLike,
                            coil_impedance: ArrayLike,
                            numerator: np.ndarray | None = None) -> np.ndarray:
    """:func:`coil_transfer_function` of many coils on one cable and DAQ input at once.

    The coils (the designs of one coil sweep) differ in their impedance and winding
    capacitance; the cable and DAQ input (``cable_capacitance``, ``input_resistance``,
    ``input_capacitance``, ``cable_resistance``) are ``load``'s.

    Parameters
    ----------
    load : ReadoutCircuit
        Any of the circuits: its cable and DAQ input are used.
    winding_capacitance : array_like, shape (m,)
        Each coil's C_w, F.
    f : array_like, shape (n,)
        Frequencies, Hz (>= 0).
    coil_impedance : array_like of complex, shape (m, n)
        Each coil's Z_s at ``f``, Ω.
    numerator : ndarray of complex, shape (m, n), optional
        Spectra to filter (e.g. the coils' EMF): returns ``numerator * H``, formed in the
        same pass as H.

    Returns
    -------
    ndarray of complex, shape (m, n)
        Row k equals ``coil_transfer_function(c_k, f, coil_impedance[k])`` (times
        ``numerator[k]``) for ``c_k`` the circuit ``load`` with winding capacitance
        ``winding_capacitance[k]``.
    """
    f = np.asarray(f, dtype=float)
    z = np.asarray(coil_impedance, dtype=complex)
    c_w = np.asarray(winding_capacitance, dtype=float)
    require(c_w.ndim == 1 and z.shape == (c_w.size, *f.shape),
            f"coil_impedance must have shape (coils, frequencies) = "
            f"{(c_w.size, *f.shape)}, got {z.shape}")
    s, _, y_b = _admittances(load, f)
    # _transfer's formula, its temporaries (coils × frequencies) formed once, in place
    h = s * c_w[:, None]
    if load.cable_resistance == 0.0:  # div = 1
        h += y_b
        h *= z
        h += 1.0
    else:
        div = 1.0 + load.cable_resistance * y_b
        h += y_b / div
        h *= z
        h += 1.0
        h *= div
    if numerator is None:
        return np.divide(1.0, h, out=h)
    return np.divide(numerator, h, out=h)


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
    g_in = c.input_conductance
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


@dataclass(frozen=True)
class ResonanceFigures:
    """Figures of the second-order read-out (R_c = 0), each of the input arrays' shape.

    Attributes
    ----------
    resonance_hz : ndarray
        f0 = ω0 / 2π, ω0² = (1 + R G) / (L C), Hz.
    quality_factor : ndarray
        Q = ω0 / β, β = R / L + G / C (the poles' sum is −β).
    bandwidth_hz : ndarray
        The −3 dB frequency: where |H(f)| = |H(0)| / √2, Hz.
    decay_s : ndarray
        1 / (decay rate of the slowest pole), s.
    """

    resonance_hz: np.ndarray
    quality_factor: np.ndarray
    bandwidth_hz: np.ndarray
    decay_s: np.ndarray


def resonance_figures(resistance: ArrayLike, inductance: ArrayLike, capacitance: ArrayLike,
                      conductance: ArrayLike) -> ResonanceFigures:
    """Resonance, Q, −3 dB bandwidth and slowest decay of second-order read-outs, in closed
    form and vectorised (a coil sweep's circuits at once).

    The circuit is :class:`ReadoutCircuit` with R_c = 0: EMF − R − L into C = C_w + C_B
    across G = 1 / R_in, so H(s) = 1 / (1 + (R + sL)(G + sC)) and its poles solve
    s² + β s + ω0² = 0 with β = R/L + G/C, ω0² = (1 + RG)/(LC).

    Bandwidth: with x = ω², |H|⁻² = (a − LC x)² + b² x (a = 1 + RG, b = RC + LG), a
    quadratic in x that starts at a² = |H(0)|⁻², so |H|² = |H(0)|²/2 at its one positive
    root of L²C² x² + (b² − 2aLC) x − a² = 0 (below it the gain is higher: a resonance peak
    is inside the band). Each root is taken in the form free of cancellation.

    Decay: an underdamped pair (β² < 4ω0²) decays at β/2; an overdamped one at its slower
    real pole, ω0² / (β/2 + √(β²/4 − ω0²)).

    Parameters
    ----------
    resistance, inductance, capacitance : array_like
        R (Ω, > 0), L (H, > 0), C (F, > 0); broadcast together.
    conductance : array_like
        G = 1 / R_in, S (>= 0).
    """
    r, ell, c, g = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                          (resistance, inductance, capacitance, conductance)))
    require(bool(np.all(ell > 0)) and bool(np.all(c > 0)),
            "the read-out's resonance needs coil inductance > 0 H and winding + cable + "
            "input capacitance > 0 F")
    a = 1.0 + r * g
    lc = ell * c
    omega0 = np.sqrt(a / lc)
    beta = r / ell + g / c
    b = r * c + ell * g
    p = b * b - 2.0 * a * lc
    root = np.sqrt(p * p + 4.0 * (lc * a) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(p > 0, 2.0 * a * a / (p + root), (root - p) / (2.0 * lc * lc))
        disc = 0.25 * beta * beta - omega0 * omega0
        rate = np.where(disc < 0, 0.5 * beta,
                        omega0 * omega0 / (0.5 * beta + np.sqrt(np.maximum(disc, 0.0))))
    return ResonanceFigures(resonance_hz=omega0 / (2.0 * math.pi), quality_factor=omega0 / beta,
                            bandwidth_hz=np.sqrt(x) / (2.0 * math.pi), decay_s=1.0 / rate)


def _second_order(circuit: ReadoutCircuit) -> ResonanceFigures:
    return resonance_figures(circuit.resistance, circuit.inductance,
                             circuit.total_capacitance, circuit.input_conductance)


def resonance(circuit: ReadoutCircuit) -> tuple[float, float]:
    """Self-resonance frequency f0 (Hz) and quality factor Q of the coil read-out.

    From the two poles of smallest magnitude p1, p2 (the coil–capacitance pair; with
    R_c > 0 the third pole is the fast R_c pole): ω0 = √(p1 p2), Q = ω0 / (−(p1 + p2)).
    For a complex pair −σ ± jω_d this is ω0 = |p|, Q = |p|/(2σ); for R_c = 0 (closed form,
    :func:`resonance_figures`) ω0² = (1 + R/R_in)/(L C) and Q = ω0 L C / (R C + L/R_in).
    """
    if circuit.cable_resistance == 0.0:
        fig = _second_order(circuit)
        return float(fig.resonance_hz), float(fig.quality_factor)
    p = poles(circuit)[:2]
    omega0 = math.sqrt(abs((p[0] * p[1]).real))
    return omega0 / (2.0 * math.pi), omega0 / float(-(p[0] + p[1]).real)


def peak_gain(circuit: ReadoutCircuit,
              coil_impedance: Callable[[np.ndarray], np.ndarray] | None = None,
              band: tuple[float, float] = (1e3, 2e6)) -> tuple[float, float]:
    """The read-out's resonance: the largest gain |H(f)| = |V_daq / EMF| and its frequency.

    :func:`resonance` gives the R + sL circuit's pole pair; this is the peak of the gain
    itself, for the lumped coil or for a coil impedance Z(f) that eddy currents make
    frequency dependent (their losses lower the peak and move it).

    Parameters
    ----------
    circuit : ReadoutCircuit
    coil_impedance : callable, optional
        Z_s(f), Ω, of an array of frequencies (Hz), e.g.
        :meth:`msens.magnetics.frequency_response.FrequencyResponse.impedance_at`; None: the
        circuit's R + sL.
    band : (float, float)
        Frequencies searched, Hz: 4000 log-spaced points, then the bracket of the largest
        refined to 1e-9 relative.

    Returns
    -------
    f_peak : float
        Hz.
    gain : float
        The gain at ``f_peak``, dimensionless (1 at DC for an unloaded coil).
    """
    lo, hi = (float(b) for b in band)
    if not 0.0 < lo < hi:
        raise InputError(f"peak_gain band must be 0 < low < high Hz, got {band}")

    def gain(f: np.ndarray) -> np.ndarray:
        f = np.atleast_1d(np.asarray(f, dtype=float))
        if coil_impedance is None:
            return np.abs(transfer_function(circuit, f))
        return np.abs(coil_transfer_function(circuit, f, coil_impedance(f)))

    grid = np.geomspace(lo, hi, 4000)
    k = int(np.argmax(gain(grid)))
    a, b = np.log(grid[max(k - 1, 0)]), np.log(grid[min(k + 1, grid.size - 1)])
    best = optimize.minimize_scalar(lambda x: -gain(np.exp(x))[0], bounds=(a, b),
                                    method="bounded", options={"xatol": 1e-9})
    f_peak = float(np.exp(best.x))
    return f_peak, float(gain(f_peak)[0])


def bandwidth(circuit: ReadoutCircuit) -> float:
    """−3 dB bandwidth, Hz: the lowest f at which |H(f)| falls to |H(0)|/√2.

    Above any resonance peak: the peak itself (|H| > |H(0)|) is inside the band. With
    R_c = 0 in closed form (:func:`resonance_figures`); with R_c > 0 the first crossing on a
    logarithmic grid around the resonance, refined by Brent's method.
    """
    if circuit.cable_resistance == 0.0:
        return float(_second_order(circuit).bandwidth_hz)
    return _bandwidth_search(circuit)


def _bandwidth_search(circuit: ReadoutCircuit) -> float:
    """:func:`bandwidth` of any circuit by search (the third-order one's; the closed form's
    check in the tests)."""
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


def compile_recursion() -> None:
    """Compile (or load from numba's cache) the read-out's state recursion for the argument
    types its first-order-hold callers pass (a read-only view of the matrix exponential,
    contiguous vectors: :func:`msens.readout.daq._foh_matrices`); ``msens run`` calls it while
    it waits for the chain kernel's first compilation (2.5 s of compiling otherwise done
    after it)."""
    e = np.eye(3)
    e.flags.writeable = False
    _linear_recursion(e[:2, :2], np.zeros(2), np.zeros((1, 2)))


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
