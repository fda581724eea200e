"""The physics MsS read-out: a coil's contact states -> EMF -> circuit -> the DAQ's record.

One function, :func:`mss_signals`, assembles the signal of a physics MsS for every workflow
(``msens run``, and through the run's records ``synth``; ``diagnose`` for each model state):

1. the contact forces and approaches of the coil's contacts (:func:`contact_rates`; the
   approaches read through the transducer's nonlinear contact maps, if any);
2. the open-circuit EMF V = -Σ_c [(∂Λ/∂F_c) dF_c/dt + (∂Λ/∂δ_c) dδ_c/dt] (Villari and contact
   approach, sensitivities from the transducer, :mod:`msens.magnetics.transducer`);
3. the read-out circuit (:func:`readout`: coil resistance and bias-point inductance, the
   winding capacitance of :mod:`msens.readout.coil`, cable, DAQ input;
   :mod:`msens.readout.electronics`);
4. the DAQ's sampling (and, if asked, its noise, :mod:`msens.readout.noise`).

Without eddy currents the EMF is formed in time and the circuit's response computed exactly
for a piecewise-linear EMF (:func:`msens.readout.daq.daq_voltage`). With eddy currents (a
frequency ``response`` of the coil) the contact rates are Fourier transformed, weighted by
S_c(ω), D_c(ω) and the circuit's transfer function with the coil's impedance Z(ω), and
transformed back. The *flux change* ΔΛ(t) — what an integrated coil voltage measures —
divided by Σ_c ∂Λ/∂F_c is a sensitivity-weighted mean contact force in newtons, comparable
with the paper's four-contact average.

The transducer and the frequency response are read through their attributes
(:class:`CoilModel`, :class:`CoilResponse`): this module knows arrays and records, not the
field model that makes them; the coil is the one :class:`msens.readout.coil.Coil`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft, rfftfreq
from scipy.integrate import cumulative_trapezoid

from msens.errors import internal, require
from msens.mechanics.hertz import hertz_approach
from msens.readout.coil import Coil, winding_capacitance
from msens.readout.daq import daq_voltage
from msens.readout.electronics import ElectronicsSpec, ReadoutCircuit, coil_transfer_function
from msens.readout.noise import NoiseModel, add_readout_noise, daq_capacitance, total_noise_rms
from msens.signals.features import integrated

#: FFT length of the frequency-domain read-out in record lengths (zero padding: the circuit's
#: ring-down after the record must fit in it; run and design use the same).
PAD = 2.0

#: The mechanisms an EMF can be formed from.
MECHANISMS = ("villari", "approach", "both")


class CoilModel(Protocol):
    """What the read-out reads of a coil's transducer
    (:class:`msens.magnetics.transducer.Transducer`)."""

    contacts: np.ndarray  # 1-based contact numbers, shape (n_c,)
    contact_stiffness: float  # Hertz prefactor A, N/m^1.5
    sensitivity_villari: np.ndarray  # ∂Λ/∂F_c, Wb/N, shape (n_c,)
    dlambda_dapproach: np.ndarray  # ∂Λ/∂δ_c, Wb/m, shape (n_c,)
    resistance_ohm: float
    inductance_H: float

    def equivalent_approach(self, delta: np.ndarray) -> np.ndarray: ...

    def sensitivity(self, mechanism: str = "both") -> np.ndarray: ...


class CoilResponse(Protocol):
    """What the read-out reads of a coil's eddy-current frequency response
    (:class:`msens.magnetics.frequency_response.FrequencyResponse`)."""

    contacts: np.ndarray

    def villari_at(self, f: np.ndarray) -> np.ndarray: ...

    def approach_at(self, f: np.ndarray) -> np.ndarray: ...

    def impedance_at(self, f: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class ContactRates:
    """Rates of the contacts a transducer reads, for one chain history.

    Attributes
    ----------
    t : ndarray, shape (nt,)
        s.
    force : ndarray, shape (nt, n_c)
        dF_c/dt, N/s (zero for contacts beyond the chain's columns).
    approach : ndarray, shape (nt, n_c)
        dδ_c/dt of the contact approaches, m/s.
    """

    t: np.ndarray
    force: np.ndarray
    approach: np.ndarray


def contact_columns(force: np.ndarray, contacts: np.ndarray,
                      columns: np.ndarray | None = None) -> np.ndarray:
    """The columns of ``contacts`` from a chain's per-contact records (forces, approaches),
    zeros where absent.

    Parameters
    ----------
    force : ndarray, shape (nt, m)
        Per-contact records: contact forces (N), approaches (m), ...
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers wanted.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force`` (sorted); default column k is contact
        k + 1 (as in :mod:`msens.chain`).

    Returns
    -------
    ndarray, shape (nt, n_c)
    """
    f = np.asarray(force, dtype=float)
    contacts = np.asarray(contacts, dtype=int)
    if columns is None:
        columns = np.arange(1, f.shape[1] + 1)
    columns = np.asarray(columns, dtype=int)
    k = np.clip(np.searchsorted(columns, contacts), 0, max(columns.size - 1, 0))
    use = (columns.size > 0) & (columns[k] == contacts)
    if k.size and use.all() and np.all(np.diff(k) == 1):
        return f[:, k[0]:k[-1] + 1].copy()  # consecutive columns: a slice, no gather
    out = np.zeros((f.shape[0], contacts.size))
    out[:, use] = f[:, k[use]]
    return out


def contact_rates(t: np.ndarray, force: np.ndarray, contacts: np.ndarray,
                  stiffness: float, columns: np.ndarray | None = None,
                  approach: np.ndarray | None = None,
                  equivalent: Callable[[np.ndarray], np.ndarray] | None = None
                  ) -> ContactRates:
    """Force and approach rates of ``contacts`` from a chain's contact states.

    Parameters
    ----------
    t : ndarray, shape (nt,)
        Strictly increasing times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers.
    stiffness : float
        Hertz prefactor A, N/m^1.5.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force`` (see :func:`contact_columns`).
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches δ_c(t), m (negative: open), same columns as
        ``force``. Without it δ_c = ([F_c]_+/A)^{2/3}, whose slope in F is infinite at
        F = 0: a contact that unloads or opens between two samples then gives a spike.
    equivalent : callable, optional
        Maps the approaches (nt, n_c) of ``contacts`` to those the linear sources read:
        the transducer's ``equivalent_approach`` (its nonlinear contact maps). Every reading
        of a chain history passes its transducer's here.

    Notes
    -----
    Rates are :func:`numpy.gradient` (second order, also on non-uniform times).
    """
    t = np.asarray(t, dtype=float)
    require(t.ndim == 1 and t.size >= 2, "t must be 1-D with at least 2 samples")
    require(bool(np.all(np.diff(t) > 0)), "t must be strictly increasing")
    require(np.ndim(force) == 2 and np.shape(force)[0] == t.size,
            f"force must have shape (nt={t.size}, n_contacts), got "
            f"{np.shape(force)}")
    fc = contact_columns(force, contacts, columns)
    delta = hertz_approach(fc, stiffness) if approach is None else \
        contact_columns(approach, contacts, columns)
    if equivalent is not None:
        delta = equivalent(delta)
    step = t[1] - t[0]
    # uniform sampling (the chain's output): numpy's scalar-spacing form, the same second-
    # order differences without per-sample spacing coefficients
    spacing = step if np.allclose(np.diff(t), step, rtol=1e-9, atol=0.0) else t
    return ContactRates(t=t, force=np.gradient(fc, spacing, axis=0),
                        approach=np.gradient(delta, spacing, axis=0))


def emf_from_rates(rates: ContactRates, sensitivity_villari: np.ndarray,
                   dlambda_dapproach: np.ndarray, mechanism: str = "both") -> np.ndarray:
    """Open-circuit EMF V = -Σ_c [(∂Λ/∂F_c) dF_c/dt + (∂Λ/∂δ_c) dδ_c/dt], V.

    Parameters
    ----------
    rates : ContactRates
    sensitivity_villari, dlambda_dapproach : ndarray, shape (..., n_c)
        Wb/N and Wb/m; leading axes (e.g. coil designs) broadcast.
    mechanism : {"villari", "approach", "both"}

    Returns
    -------
    ndarray, shape (..., nt)
    """
    require(mechanism in MECHANISMS,
            f"mechanism must be one of {', '.join(MECHANISMS)}, got {mechanism!r}")
    out = 0.0
    if mechanism in ("villari", "both"):
        out = out - np.asarray(sensitivity_villari) @ rates.force.T
    if mechanism in ("approach", "both"):
        out = out - np.asarray(dlambda_dapproach) @ rates.approach.T
    return out


def emf_spectrum(villari: np.ndarray, approach: np.ndarray, force_rate: np.ndarray,
                 approach_rate: np.ndarray) -> np.ndarray:
    """EMF(ω) = −Σ_c [S_c(ω) Ḟ_c(ω) + D_c(ω) δ̇_c(ω)] of one or many coils.

    Parameters
    ----------
    villari, approach : ndarray of complex, shape (n, ..., n_c)
        S_c (Wb/N) and D_c (Wb/m) at the n frequencies of the spectra.
    force_rate, approach_rate : ndarray of complex, shape (n, n_c)
        Spectra of dF_c/dt (N/s per bin) and dδ_c/dt (m/s per bin), the coils' contacts.

    Returns
    -------
    ndarray of complex, shape (n, ...)
    """
    s, d = villari, approach
    shape = (s.shape[0],) + (1,) * (s.ndim - 2) + (s.shape[-1],)
    return -(np.sum(s * np.reshape(force_rate, shape), axis=-1)
             + np.sum(d * np.reshape(approach_rate, shape), axis=-1))


@dataclass(frozen=True)
class MssRecord:
    """What one physics MsS produces for one chain run.

    Attributes
    ----------
    t : ndarray, shape (nt,)
        Chain output times, s.
    flux : ndarray, shape (nt,)
        Change of the coil's flux linkage ΔΛ(t), Wb.
    weighted_force : ndarray, shape (nt,)
        ΔΛ / Σ_c ∂Λ/∂F_c, N: the sensitivity-weighted mean dynamic contact force.
    emf : ndarray, shape (nt,)
        Open-circuit EMF, V.
    t_daq, voltage : ndarray, shape (m,)
        DAQ sampling instants (s) and the voltage recorded there (V).
    circuit : ReadoutCircuit
    sensitivity : float
        Σ_c ∂Λ/∂F_c of both mechanisms at the reference load, Wb/N: the scale of
        ``weighted_force`` and :attr:`daq_force`.
    """

    t: np.ndarray
    flux: np.ndarray
    weighted_force: np.ndarray
    emf: np.ndarray
    t_daq: np.ndarray
    voltage: np.ndarray
    circuit: ReadoutCircuit
    sensitivity: float = float("nan")

    @property
    def integrated_voltage(self) -> np.ndarray:
        """Running integral of the DAQ voltage from ``t[0]`` on the chain's grid, V s,
        shape (nt,): the record a measured physics MsS gives its features from."""
        return integrated(voltage_on(self), self.t)

    @property
    def daq_force(self) -> np.ndarray:
        """The integrated DAQ voltage in newtons of sensitivity-weighted contact force,
        −∫V dt / Σ_c ∂Λ/∂F_c, shape (nt,): ``weighted_force`` as the read-out circuit
        delivers it (the coil's resonance reshapes the pulse); the physics MsS's feature
        record in ``msens run``."""
        if not self.sensitivity:
            return np.full(self.t.shape, np.nan)
        return -self.integrated_voltage / self.sensitivity


@dataclass(frozen=True)
class MssSensor:
    """A physics MsS as an observation operator: its transducer and read-out circuit.

    Attributes
    ----------
    transducer : CoilModel
        :class:`msens.magnetics.transducer.Transducer`.
    circuit : ReadoutCircuit
    """

    transducer: CoilModel
    circuit: ReadoutCircuit


def readout(coil: Coil, resistance: float, inductance: float,
            electronics: ElectronicsSpec) -> ReadoutCircuit:
    """A coil's read-out circuit: its R (Ω) and bias-point L (H), the winding capacitance
    estimate of :mod:`msens.readout.coil`, the study's cable and DAQ input. The one place a
    coil's circuit is built, for runs, diagnoses and design sweeps alike."""
    return ReadoutCircuit(resistance=resistance, inductance=inductance,
                          winding_capacitance=winding_capacitance(coil),
                          cable_capacitance=electronics.cable_capacitance_f,
                          input_resistance=electronics.input_resistance_ohm,
                          input_capacitance=electronics.input_capacitance_f)


def noise_model(electronics: ElectronicsSpec) -> NoiseModel | None:
    """The study's noise settings, or None when every source is off."""
    if not (electronics.johnson_noise or electronics.adc_bits
            or electronics.input_noise_v_per_rthz > 0):
        return None
    # Johnson noise is generated at temperature_K; a zero temperature switches it off.
    return NoiseModel(temperature_K=electronics.temperature_k if electronics.johnson_noise
                      else 0.0,
                      adc_bits=electronics.adc_bits, adc_range_V=electronics.adc_range_v,
                      input_noise_V_per_rtHz=electronics.input_noise_v_per_rthz)


def figure_noise_rms(circuit: ReadoutCircuit, electronics: ElectronicsSpec) -> float:
    """RMS noise at the DAQ for figures of merit, V: Johnson noise of the circuit at the
    study's temperature (whether or not the study adds it to its records), the DAQ's input
    noise and quantisation, over all frequencies (per sample)."""
    return float(figure_noise_rms_of(daq_capacitance(circuit), electronics))


def figure_noise_rms_of(capacitance: np.ndarray, electronics: ElectronicsSpec) -> np.ndarray:
    """:func:`figure_noise_rms` of read-outs whose DAQ node holds ``capacitance`` (F, any
    shape: a coil sweep's circuits at once; :func:`msens.readout.noise.total_noise_rms`)."""
    noise = NoiseModel(temperature_K=electronics.temperature_k, adc_bits=electronics.adc_bits,
                       adc_range_V=electronics.adc_range_v,
                       input_noise_V_per_rtHz=electronics.input_noise_v_per_rthz)
    return total_noise_rms(capacitance, noise, sample_rate=electronics.sample_rate_hz)


def voltage_on(record: MssRecord) -> np.ndarray:
    """The DAQ voltage on the chain's time grid, V, shape (nt,) (linear interpolation; exact
    where the DAQ samples at the chain's rate)."""
    return np.interp(record.t, record.t_daq, record.voltage)


def mss_signals(sensor: MssSensor, t: np.ndarray, force: np.ndarray, sample_rate: float, *,
                response: CoilResponse | None = None, approach: np.ndarray | None = None,
                static: np.ndarray | None = None, columns: np.ndarray | None = None,
                noise: NoiseModel | None = None,
                rng: np.random.Generator | int | None = None, pad: float = PAD) -> MssRecord:
    """The signals of one physics MsS for a chain's contact states: the one read-out.

    Parameters
    ----------
    sensor : MssSensor
        The coil's transducer and read-out circuit (:func:`readout`).
    t : ndarray, shape (nt,)
        Uniform chain output times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    sample_rate : float
        DAQ rate, Hz.
    response : CoilResponse, optional
        The coil's eddy-current frequency response (same contacts as the transducer): the
        frequency-domain read-out, in which it replaces the circuit's R and L by Z(ω). The
        DAQ voltage is then linearly interpolated from the chain's grid to the DAQ instants
        t[0] + k/sample_rate (exact where the DAQ samples at the chain's rate). Without it
        the time-domain read-out (exact for a piecewise-linear EMF); with σ = 0 the two
        agree to ~(ωΔt)²/12 at the signal frequencies.
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches, m (negative: open), same columns as ``force``;
        default the Hertz approach of the forces (see :func:`contact_rates`).
    static : ndarray, shape (n,), optional
        Static contact forces (column k is contact k + 1), N, the reference of ``flux``;
        default the first sample (time-domain read-out only: with eddy currents the flux is
        −∫ EMF dt).
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force``; default column k is contact k + 1.
    noise : NoiseModel, optional
        Noise of the acquisition (None: noise-free); with eddy currents the coil's Johnson
        noise from 4kT Re Z(f).
    rng : numpy.random.Generator or int, optional
        Noise seed or generator (None = seed 0).
    pad : float
        FFT length ≥ ``pad`` × nt of the frequency-domain read-out (> 1: the circuit's
        ring-down must fit in the padding).

    Returns
    -------
    MssRecord
    """
    tr = sensor.transducer
    t = np.asarray(t, dtype=float)
    contacts = np.asarray(tr.contacts, dtype=int)
    fc = contact_columns(force, contacts, columns)
    stiff = tr.contact_stiffness
    delta = (hertz_approach(fc, stiff) if approach is None
             else contact_columns(approach, contacts, columns))
    # the nonlinear contact maps, if any: what the linear sources read
    equivalent = tr.equivalent_approach(delta)
    rates = contact_rates(t, fc, contacts, stiff, columns=contacts, approach=equivalent)
    total = float(np.sum(tr.sensitivity("both")))
    if response is None:
        base = fc[0] if static is None else contact_columns(np.asarray(static)[None, :],
                                                               contacts)[0]
        delta0 = tr.equivalent_approach(hertz_approach(base, stiff))
        flux = ((fc - base) @ tr.sensitivity_villari
                + (equivalent - delta0) @ tr.dlambda_dapproach)
        e = emf_from_rates(rates, tr.sensitivity_villari, tr.dlambda_dapproach)
        t_daq, voltage = daq_voltage(sensor.circuit, t, e, sample_rate, noise=noise, rng=rng)
    else:
        internal(np.array_equal(contacts, np.asarray(response.contacts)),
                 "internal: transducer and frequency response describe different contacts")
        require(pad > 1, f"pad must be > 1, got {pad}")
        dt = (t[-1] - t[0]) / (t.size - 1)
        require(bool(np.allclose(np.diff(t), dt, rtol=1e-6, atol=0.0)),
                "chain times must be uniformly spaced")
        n = next_fast_len(math.ceil(pad * t.size), real=True)
        f = rfftfreq(n, dt)
        e_hat = emf_spectrum(response.villari_at(f), response.approach_at(f),
                             rfft(rates.force, n, axis=0), rfft(rates.approach, n, axis=0))
        h = coil_transfer_function(sensor.circuit, f, response.impedance_at(f))
        e = irfft(e_hat, n)[:t.size]
        v = irfft(h * e_hat, n)[:t.size]
        n_daq = math.floor((t[-1] - t[0]) * sample_rate * (1 + 1e-12)) + 1
        t_daq = t[0] + np.arange(n_daq) / sample_rate
        flux = -cumulative_trapezoid(e, t, initial=0.0)
        voltage = np.interp(t_daq, t, v)
        if noise is not None:
            voltage = add_readout_noise(voltage, sensor.circuit, noise, sample_rate, rng=rng,
                                        coil_impedance=response.impedance_at)
    return MssRecord(t=t, flux=flux, weighted_force=flux / total if total else flux * np.nan,
                     emf=e, t_daq=t_daq, voltage=voltage, circuit=sensor.circuit,
                     sensitivity=total)


__all__ = [
    "MECHANISMS",
    "PAD",
    "CoilModel",
    "CoilResponse",
    "ContactRates",
    "MssRecord",
    "MssSensor",
    "contact_columns",
    "contact_rates",
    "emf_from_rates",
    "emf_spectrum",
    "figure_noise_rms",
    "figure_noise_rms_of",
    "mss_signals",
    "noise_model",
    "readout",
    "voltage_on",
]
