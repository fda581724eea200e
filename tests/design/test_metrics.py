"""Vectorised circuit metrics against msens.electronics (same circuit, other algorithms)."""

from __future__ import annotations

import numpy as np
import pytest

from msens.design.metrics import circuit_metrics, peak_emf
from msens.design.report import pareto_mask
from msens.electronics import NoiseModel, ReadoutCircuit, bandwidth, noise_rms, resonance
from msens.study import ElectronicsSpec


@pytest.mark.parametrize("elec", [ElectronicsSpec(),
                                  ElectronicsSpec(input_resistance_ohm=1e4,
                                                  input_noise_v_per_rthz=5e-9, adc_bits=12,
                                                  adc_range_v=2.0)])
def test_circuit_metrics_match_electronics(elec):
    r = np.array([91.9, 20.0, 400.0])
    ind = np.array([32e-3, 1e-3, 0.2])
    cw = np.array([10.8e-12, 3e-12, 40e-12])
    m = circuit_metrics(r, ind, cw, elec)
    for k in range(3):
        c = ReadoutCircuit(r[k], ind[k], cw[k], elec.cable_capacitance_f,
                           elec.input_resistance_ohm, elec.input_capacitance_f)
        f0, q = resonance(c)
        assert m["resonance_Hz"][k] == pytest.approx(f0, rel=1e-9)
        assert m["quality_factor"][k] == pytest.approx(q, rel=1e-9)
        assert m["bandwidth_Hz"][k] == pytest.approx(bandwidth(c), rel=1e-8)
        noise = NoiseModel(temperature_K=elec.temperature_k, adc_bits=elec.adc_bits,
                           adc_range_V=elec.adc_range_v,
                           input_noise_V_per_rtHz=elec.input_noise_v_per_rthz)
        assert m["noise_rms_V"][k] == pytest.approx(
            noise_rms(c, noise, sample_rate=elec.sample_rate_hz), rel=1e-6)


def test_peak_emf_is_linear_in_sensitivity_and_rate():
    rng = np.random.default_rng(1)
    s = rng.normal(size=(5, 4))
    rate = rng.normal(size=(4, 50))
    ref = np.max(np.abs(s @ rate), axis=1)
    np.testing.assert_allclose(peak_emf(s, rate, chunk=2), ref, rtol=1e-14)
    np.testing.assert_allclose(peak_emf(3 * s, rate), 3 * ref, rtol=1e-14)


def test_pareto_mask():
    x = np.array([1.0, 2.0, 2.0, 3.0])
    y = np.array([1.0, 3.0, 2.0, 3.0])
    assert pareto_mask(x, y, "min").tolist() == [True, True, False, False]
    assert pareto_mask(x, y, "max").tolist() == [False, False, False, True]
