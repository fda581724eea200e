"""What a sensor reads: the chain's observation operators, the pick-up coil, its circuit.

- :mod:`.sensors` — observation operators: bead, rod and four-contact MsS records from the
  chain's contact forces.
- :mod:`.coil` — the pick-up coil (one type for the field model, the circuit and design):
  wire, geometry, resistance, inductance, capacitance.
- :mod:`.electronics` — the read-out circuit from the EMF to the DAQ input.
- :mod:`.daq` — the voltage the DAQ records, sampled.
- :mod:`.noise` — the circuit's noise at the DAQ.
- :mod:`.mss` — the physics MsS's read-out: contact states -> EMF -> circuit -> DAQ record,
  one function (:func:`~msens.readout.mss.mss_signals`) for run, synth and diagnose.
"""

from msens._lazy import attribute, names

_HOMES = {
    "sensors": ("SensorKind", "bead_sensor", "contact_mean", "dynamic_force",
                "mss_four_contact", "mss_four_contact_rate", "observe", "read_contacts",
                "rod_sensor", "sensor_contacts", "time_derivative", "time_integral"),
    "coil": ("WIRES", "Coil", "Wire", "awg_diameter", "coil_from", "heavy_build_diameter",
             "turn_to_turn_capacitance", "wheeler_inductance", "winding_capacitance",
             "wire_for"),
    "electronics": ("ElectronicsSpec", "ReadoutCircuit", "bandwidth", "coil_transfer_function",
                    "peak_gain", "poles", "readout_circuit", "resonance", "state_space",
                    "transfer_function"),
    "daq": ("daq_voltage",),
    "noise": ("NoiseModel", "add_readout_noise", "noise_rms", "thermal_covariance",
              "thermal_noise_psd"),
    "mss": ("ContactRates", "MssRecord", "MssSensor", "contact_columns", "contact_rates",
            "emf_from_rates", "mss_signals", "noise_model", "readout", "voltage_on"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)
