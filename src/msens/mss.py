"""Physics MsS read-out: chain contact forces -> coil EMF -> voltage at the DAQ.

The transducer (field model + Villari law + reciprocity, :mod:`msens.transducer`) gives each
contact's sensitivity ∂Λ/∂F_c; the EMF is V = -Σ_c (∂Λ/∂F_c) dF_c/dt; the coil's resistance
and bias-point inductance, its winding capacitance, the cable and the DAQ input then shape
it (:mod:`msens.electronics`). The *flux change* ΔΛ(t) = Σ_c (∂Λ/∂F_c) ΔF_c(t) — what an
integrated coil voltage measures — divided by Σ_c ∂Λ/∂F_c is a sensitivity-weighted mean
contact force in newtons, directly comparable with the paper's four-contact average.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.coil import winding_capacitance, winding_from_coil
from msens.electronics import NoiseModel, ReadoutCircuit, daq_voltage
from msens.study import CoilSpec, ElectronicsSpec
from msens.transducer import Transducer, emf


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
    """

    t: np.ndarray
    flux: np.ndarray
    weighted_force: np.ndarray
    emf: np.ndarray
    t_daq: np.ndarray
    voltage: np.ndarray
    circuit: ReadoutCircuit


def readout(transducer: Transducer, coil: CoilSpec, electronics: ElectronicsSpec
            ) -> ReadoutCircuit:
    """The coil's read-out circuit: field-model R and L, winding capacitance estimate, the
    study's cable and DAQ input."""
    winding = winding_from_coil(coil.turns, coil.length_m, coil.inner_radius_m, coil.wire)
    return ReadoutCircuit(resistance=transducer.resistance_ohm,
                          inductance=transducer.inductance_H,
                          winding_capacitance=winding_capacitance(winding),
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


def mss_record(transducer: Transducer, circuit: ReadoutCircuit, t: np.ndarray,
               force: np.ndarray, electronics: ElectronicsSpec, *,
               static: np.ndarray | None = None, seed_offset: int = 0) -> MssRecord:
    """Coil signals of one physics MsS for contact forces ``force`` (nt, n), N.

    Parameters
    ----------
    static : ndarray, shape (n,), optional
        Static contact forces, N; default the first sample.
    seed_offset : int
        Added to the study's noise seed so that two coils get independent noise.
    """
    s = transducer.sensitivity("both")
    cols = np.asarray(transducer.contacts, dtype=int) - 1
    use = cols < force.shape[1]
    base = force[0] if static is None else static
    flux = (force[:, cols[use]] - base[cols[use]]) @ s[use]
    total = float(np.sum(s[use]))
    e = emf(transducer, t, force)
    t_daq, v = daq_voltage(circuit, t, e, electronics.sample_rate_hz,
                           noise=noise_model(electronics),
                           rng=electronics.seed + seed_offset)
    return MssRecord(t=t, flux=flux, weighted_force=flux / total if total else flux * np.nan,
                     emf=e, t_daq=t_daq, voltage=v, circuit=circuit)
