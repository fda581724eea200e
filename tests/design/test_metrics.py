"""Design figures of merit against the run's read-out (same functions, other algorithms)."""

from __future__ import annotations

import numpy as np
import pytest

from msens.design.metrics import Wave, design_rows
from msens.design.report import pareto_mask, range_edges
from msens.design.sweep import Design
from msens.field.parts import Coil
from msens.magnetics.emf import contact_rates, emf_from_rates
from msens.params.units import K_B
from msens.readout.daq import daq_voltage
from msens.readout.electronics import ElectronicsSpec
from msens.readout.mss import readout


def _wave(n_c: int = 3) -> Wave:
    """``n_c`` contacts (from 12 on) loaded by smooth solitary-like pulses 30 µs apart,
    10 MHz over 400 µs."""
    t = np.arange(4001) * 1e-7
    centres = 100e-6 + 30e-6 * np.arange(n_c)
    force = 2.0 + 8.0 / np.cosh((t[:, None] - centres) / 8e-6) ** 2
    contacts = np.arange(12, 12 + n_c)
    full = np.zeros((t.size, 20))
    full[:, contacts - 1] = force
    return Wave(contacts=contacts, rates=contact_rates(t, full, contacts, 1.2e10),
                precompression_N=2.0, precompression_max_N=2.5, wave_speed_change=0.1)


@pytest.mark.parametrize("elec", [ElectronicsSpec(),
                                  ElectronicsSpec(input_resistance_ohm=1e4,
                                                  input_noise_v_per_rthz=5e-9, adc_bits=12,
                                                  adc_range_v=2.0)])
def test_rows_equal_the_run_readout(elec):
    wave = _wave()
    coils = [Coil(particle=13), Coil(particle=13, turns=600, length=9e-3)]
    s_vil = np.array([[1e-8, 2e-8, -1e-8], [3e-9, 1e-8, 0.0]])
    dl = np.array([[-1e-2, -3e-2, 1e-2], [-5e-3, -1e-2, 2e-3]])
    res, ind = np.array([91.9, 40.0]), np.array([32e-3, 9e-3])
    rows = design_rows(coils, res, ind, s_vil, dl, wave, elec)
    for k, row in enumerate(rows):
        e = emf_from_rates(wave.rates, s_vil[k], dl[k])
        assert row["peak_emf_V"] == pytest.approx(float(np.max(np.abs(e))), rel=1e-14)
        circuit = readout(coils[k], res[k], ind[k], elec)
        _, v = daq_voltage(circuit, wave.rates.t, e, elec.sample_rate_hz)
        # FFT of the sampled EMF against the exact first-order hold: same circuit
        assert row["peak_voltage_V"] == pytest.approx(float(np.max(np.abs(v))), rel=2e-3)
        assert row["snr"] == pytest.approx(row["peak_voltage_V"] / row["noise_rms_V"])
    # Johnson noise of a circuit with one capacitive node is kT/C (equipartition)
    if elec.input_noise_v_per_rthz == 0 and elec.adc_bits is None:
        c_total = readout(coils[0], res[0], ind[0], elec).total_capacitance
        assert rows[0]["noise_rms_V"] == pytest.approx(
            np.sqrt(K_B * elec.temperature_k / c_total), rel=1e-6)


def test_range_edges_flags_the_bounds_of_numeric_parameters():
    designs = [Design(i, (("coil.turns", n), ("coil.wire", w)))
               for i, (n, w) in enumerate([(400, "AWG36"), (800, "AWG36"), (1200, "AWG38")])]
    assert range_edges(designs, 2) == [("coil.turns", 1200.0, "upper end")]
    assert range_edges(designs, 1) == []
    assert range_edges(designs, 0) == [("coil.turns", 400.0, "lower end")]


def test_pareto_mask():
    x = np.array([1.0, 2.0, 2.0, 3.0])
    y = np.array([1.0, 3.0, 2.0, 3.0])
    assert pareto_mask(x, y, "min").tolist() == [True, True, False, False]
    assert pareto_mask(x, y, "max").tolist() == [False, False, False, True]
