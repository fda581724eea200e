"""Physics MsS read-out: chain contact forces -> coil EMF -> voltage at the DAQ.

The transducer (:mod:`msens.magnetics.transducer`) gives each contact's Villari sensitivity
∂Λ/∂F_c and contact-approach sensitivity ∂Λ/∂δ_c; the EMF is
V = -Σ_c [(∂Λ/∂F_c) dF_c/dt + (∂Λ/∂δ_c) dδ_c/dt]. The read-out circuit (coil resistance and
bias-point inductance, winding capacitance, cable, DAQ input; :mod:`msens.readout.electronics`) then
shapes it: :func:`readout` is the one place a coil's circuit is built, for runs and design
sweeps alike. The *flux change* ΔΛ(t) — what an integrated coil voltage measures — divided by
Σ_c ∂Λ/∂F_c (both mechanisms, at the reference load) is a sensitivity-weighted mean contact
force in newtons, comparable with the paper's four-contact average.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.field.parts import Coil
from msens.magnetics.emf import contact_forces_of, contact_rates, emf_from_rates
from msens.magnetics.transducer import Transducer
from msens.mechanics.hertz import hertz_approach
from msens.readout.coil import Winding, winding_capacitance, winding_from_coil
from msens.readout.daq import daq_voltage
from msens.readout.electronics import ElectronicsSpec, ReadoutCircuit
from msens.readout.noise import NoiseModel, noise_rms
from msens.signals.features import integrated


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


def winding_of(coil: Coil) -> Winding:
    """The :mod:`msens.readout.coil` winding of a field-model coil (same wire, packing, size)."""
    return winding_from_coil(coil.turns, coil.length, coil.inner_radius, coil.wire.name,
                             coil.packing_factor, insulated_diameter=coil.wire.insulated_diameter)


def readout(coil: Coil, resistance: float, inductance: float,
            electronics: ElectronicsSpec) -> ReadoutCircuit:
    """A coil's read-out circuit: its R (Ω) and bias-point L (H), the winding capacitance
    estimate of :mod:`msens.readout.coil`, the study's cable and DAQ input."""
    return ReadoutCircuit(resistance=resistance, inductance=inductance,
                          winding_capacitance=winding_capacitance(winding_of(coil)),
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
    noise = NoiseModel(temperature_K=electronics.temperature_k, adc_bits=electronics.adc_bits,
                       adc_range_V=electronics.adc_range_v,
                       input_noise_V_per_rtHz=electronics.input_noise_v_per_rthz)
    return noise_rms(circuit, noise, sample_rate=electronics.sample_rate_hz)


@dataclass(frozen=True)
class MssSensor:
    """A physics MsS as an observation operator: its transducer and read-out circuit.

    Attributes
    ----------
    transducer : Transducer
    circuit : ReadoutCircuit
    """

    transducer: Transducer
    circuit: ReadoutCircuit


def mss_signals(sensor: MssSensor, t: np.ndarray, force: np.ndarray, sample_rate: float, *,
                approach: np.ndarray | None = None, static: np.ndarray | None = None,
                columns: np.ndarray | None = None, noise: NoiseModel | None = None,
                rng: int | None = None) -> MssRecord:
    """Coil signals of one physics MsS for a chain's contact forces.

    Parameters
    ----------
    sensor : MssSensor
    t : ndarray, shape (nt,)
        Uniform chain output times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    sample_rate : float
        DAQ rate, Hz.
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches, m (negative: open), same columns as ``force``;
        default the Hertz approach of the forces (see
        :func:`msens.magnetics.emf.contact_rates`).
    static : ndarray, shape (n,), optional
        Static contact forces (column k is contact k + 1), N; default the first sample.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force``; default column k is contact k + 1.
    noise : NoiseModel, optional
        Noise of the acquisition (None: noise-free).
    rng : int, optional
        Noise seed.
    """
    tr = sensor.transducer
    contacts = np.asarray(tr.contacts, dtype=int)
    fc = contact_forces_of(force, contacts, columns)
    base = fc[0] if static is None else contact_forces_of(np.asarray(static)[None, :],
                                                           contacts)[0]
    stiff = tr.contact_stiffness
    delta0 = hertz_approach(base, stiff)
    if approach is None:
        delta = hertz_approach(fc, stiff)
    else:
        delta = contact_forces_of(approach, contacts, columns)
    # the nonlinear contact maps, if any: what the linear sources read
    delta, delta0 = tr.equivalent_approach(delta), tr.equivalent_approach(delta0)
    flux = (fc - base) @ tr.sensitivity_villari + (delta - delta0) @ tr.dlambda_dapproach
    total = float(np.sum(tr.sensitivity("both")))
    rates = contact_rates(t, fc, contacts, stiff, columns=contacts, approach=delta)
    e = emf_from_rates(rates, tr.sensitivity_villari, tr.dlambda_dapproach)
    t_daq, v = daq_voltage(sensor.circuit, t, e, sample_rate, noise=noise, rng=rng)
    return MssRecord(t=t, flux=flux, weighted_force=flux / total if total else flux * np.nan,
                     emf=e, t_daq=t_daq, voltage=v, circuit=sensor.circuit,
                     sensitivity=total)


def voltage_on(record: MssRecord) -> np.ndarray:
    """The DAQ voltage on the chain's time grid, V, shape (nt,) (linear interpolation; exact
    where the DAQ samples at the chain's rate)."""
    return np.interp(record.t, record.t_daq, record.voltage)


def mss_record(transducer: Transducer, circuit: ReadoutCircuit, t: np.ndarray,
               force: np.ndarray, electronics: ElectronicsSpec, *,
               approach: np.ndarray | None = None, static: np.ndarray | None = None,
               seed_offset: int = 0) -> MssRecord:
    """Coil signals of one physics MsS of a study for contact forces ``force`` (nt, n), N.

    Parameters
    ----------
    approach : ndarray, shape (nt, n), optional
        The chain's contact approaches, m.
    static : ndarray, shape (n,), optional
        Static contact forces, N; default the first sample.
    seed_offset : int
        Added to the study's noise seed so that two coils get independent noise.
    """
    return mss_signals(MssSensor(transducer, circuit), t, force, electronics.sample_rate_hz,
                       approach=approach, static=static, noise=noise_model(electronics),
                       rng=electronics.seed + seed_offset)
