"""The physics MsS read-out (msens.readout.mss.mss_signals): one function for run, synth and
diagnose, checked against a closed form.

A coil that reads one contact with a Villari sensitivity S (Wb/N) sees the EMF
e(t) = -S dF/dt. For F = F0 + A sin(ωt) that is -S A ω cos(ωt); through a series R-L coil
loaded by a capacitance C (no DAQ resistance) the DAQ voltage settles to
Re[H(jω) (-S A ω) e^{jωt}] with H = 1 / (1 + (R + jωL) jωC), the textbook RLC divider,
written out here, not taken from msens. Both read-outs (time domain, and with a flat
frequency response, the eddy-current one) must give it once the start-up transient
(decay rate R/2L) has died out.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from msens.errors import InternalError
from msens.readout.electronics import ReadoutCircuit
from msens.readout.mss import MssSensor, mss_signals, voltage_on

R, L, C = 1e3, 10e-3, 1e-9  # Ω, H, F: resonance 50 kHz, decay rate R/2L = 5e4 1/s
S = -2e-6  # Wb/N
F0, A, FREQ = 3.0, 0.5, 20e3  # N, N, Hz


class OneContact:
    """A transducer stub: one contact, Villari only."""

    def __init__(self) -> None:
        self.contacts = np.array([1])
        self.contact_stiffness = 1e10
        self.sensitivity_villari = np.array([S])
        self.dlambda_dapproach = np.array([0.0])
        self.resistance_ohm = R
        self.inductance_H = L

    def equivalent_approach(self, delta):
        return delta

    def sensitivity(self, mechanism="both"):
        return self.sensitivity_villari


class FlatResponse:
    """A frequency response without eddy currents: S at every frequency, Z = R + jωL."""

    def __init__(self, contact: int = 1) -> None:
        self.contacts = np.array([contact])

    def villari_at(self, f):
        return np.full((np.size(f), 1), S, dtype=complex)

    def approach_at(self, f):
        return np.zeros((np.size(f), 1), dtype=complex)

    def impedance_at(self, f):
        return R + 2j * np.pi * np.asarray(f) * L


def _circuit():
    return ReadoutCircuit(resistance=R, inductance=L, winding_capacitance=C,
                          cable_capacitance=0.0, input_resistance=np.inf,
                          input_capacitance=0.0)


def _force():
    t = np.arange(5001) * 1e-7  # 0.5 ms at 10 MHz
    return t, (F0 + A * np.sin(2 * np.pi * FREQ * t))[:, None]


def _closed_form(t):
    w = 2 * np.pi * FREQ
    h = 1.0 / (1.0 + (R + 1j * w * L) * 1j * w * C)
    return np.real(h * (-S * A * w) * np.exp(1j * w * t))


@pytest.mark.parametrize("response", [None, FlatResponse()], ids=["time", "frequency"])
def test_readout_is_the_rlc_response_to_the_emf(response):
    t, force = _force()
    rec = mss_signals(MssSensor(OneContact(), _circuit()), t, force, 10e6, response=response)
    settled = t > 3e-4  # the transient has decayed by exp(-15)
    expect = _closed_form(t)
    peak = np.max(np.abs(expect))
    # np.gradient's rates: (ωΔt)²/6 = 3e-5 of the amplitude
    assert np.max(np.abs(rec.voltage - expect)[settled]) < 2e-4 * peak
    w = 2 * np.pi * FREQ
    np.testing.assert_allclose(rec.emf[1:-1], (-S * A * w * np.cos(w * t))[1:-1],
                               rtol=0, atol=1e-4 * abs(S * A * w))
    # the flux change is S ΔF (up to the trapezoidal integral of the eddy read-out)
    np.testing.assert_allclose(rec.weighted_force, force[:, 0] - F0, rtol=0, atol=1e-4 * A)
    assert rec.sensitivity == S
    # the DAQ samples at the chain's rate: its record is the voltage on the chain's grid
    np.testing.assert_allclose(voltage_on(rec), rec.voltage, rtol=0, atol=1e-12 * peak)


def test_daq_force_is_the_integrated_voltage_in_newtons():
    t, force = _force()
    rec = mss_signals(MssSensor(OneContact(), _circuit()), t, force, 10e6)
    # H(0) = 1: after the transient the integrated voltage is -S ΔF(t), shifted by the
    # circuit's phase; in newtons the amplitude is A |H(jω)|
    w = 2 * np.pi * FREQ
    h = 1.0 / (1.0 + (R + 1j * w * L) * 1j * w * C)
    late = t > 3e-4
    swing = np.ptp(rec.daq_force[late])
    assert swing == pytest.approx(2 * A * abs(h), rel=1e-3)


def test_mismatched_response_is_an_internal_error():
    t, force = _force()
    with pytest.raises(InternalError):
        mss_signals(MssSensor(OneContact(), _circuit()), t, force, 10e6,
                    response=FlatResponse(contact=2))


def test_one_readout_path():
    """The coil voltage of run and diagnose comes from this one function: the second path
    (msens.magnetics.mss, eddy_readout.dynamic_signals) is gone, and diagnose calls it."""
    from msens.diagnose import physics
    from msens.magnetics import eddy_readout
    from msens.readout import mss

    assert importlib.util.find_spec("msens.magnetics.mss") is None
    assert not hasattr(eddy_readout, "dynamic_signals")
    assert physics.mss_signals is mss.mss_signals
