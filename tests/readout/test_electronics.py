"""Read-out circuit against closed-form circuit theory and noise statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from msens.errors import InputError
from msens.params.units import K_B
from msens.readout.daq import daq_voltage
from msens.readout.electronics import (
    ReadoutCircuit,
    _bandwidth_search,
    bandwidth,
    peak_gain,
    resonance,
    resonance_figures,
    state_space,
    transfer_function,
)
from msens.readout.noise import (
    NoiseModel,
    add_readout_noise,
    noise_rms,
    thermal_covariance,
    thermal_noise_psd,
    total_noise_rms,
)

T_ROOM = 293.15
#: The paper's coil (msens.readout.coil: R 91.9 Ω, Wheeler L 23.0 mH, C_w ~ 10.8 pF) on 1 m RG-58
#: into 1 MΩ ∥ 20 pF.
PAPER = ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 1e6, 20e-12)
WITH_CABLE_R = ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 1e6, 20e-12,
                              cable_resistance=50.0)


def second_order(c: ReadoutCircuit) -> tuple[float, float, float]:
    """DC gain k, ω0 and σ of H = k ω0² / (s² + 2σ s + ω0²) for R_c = 0."""
    cap = c.total_capacitance
    g = 0.0 if math.isinf(c.input_resistance) else 1.0 / c.input_resistance
    k = 1.0 / (1.0 + c.resistance * g)
    omega0 = math.sqrt((1.0 + c.resistance * g) / (c.inductance * cap))
    sigma = 0.5 * (c.resistance / c.inductance + g / cap)
    return k, omega0, sigma


def ramp_response(c: ReadoutCircuit, t: np.ndarray) -> np.ndarray:
    """Response to a unit-slope ramp starting at t = 0 (zero for t < 0), closed form.

    R(s) = k ω0²/(s² D(s)) = k [1/s² − a/s + (a s + b)/D(s)], a = 2σ/ω0², b = 4σ²/ω0² − 1.
    """
    k, w0, sig = second_order(c)
    wd = math.sqrt(w0**2 - sig**2)
    a = 2 * sig / w0**2
    b = 4 * sig**2 / w0**2 - 1
    tt = np.clip(t, 0.0, None)
    y = tt - a + np.exp(-sig * tt) * (a * np.cos(wd * tt) + (b - a * sig) / wd
                                      * np.sin(wd * tt))
    return np.where(t > 0, k * y, 0.0)


def impulse_response(c: ReadoutCircuit, t: np.ndarray) -> np.ndarray:
    k, w0, sig = second_order(c)
    wd = math.sqrt(w0**2 - sig**2)
    return np.where(t > 0, k * w0**2 / wd * np.exp(-sig * t) * np.sin(wd * t), 0.0)


# ---------------------------------------------------------------- frequency domain

@pytest.mark.parametrize("circuit", [PAPER, WITH_CABLE_R])
def test_dc_gain_is_resistive_divider(circuit):
    h0 = transfer_function(circuit, [0.0])[0]
    expected = circuit.input_resistance / (circuit.resistance + circuit.cable_resistance
                                           + circuit.input_resistance)
    assert h0 == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("circuit", [PAPER, WITH_CABLE_R])
def test_transfer_function_matches_state_space(circuit):
    a, b, c = state_space(circuit)
    f = np.geomspace(10.0, 1e8, 37)
    h_ss = [c @ np.linalg.solve(2j * np.pi * fk * np.eye(len(c)) - a, b[:, 0]) for fk in f]
    np.testing.assert_allclose(transfer_function(circuit, f), h_ss, rtol=1e-9)


def test_resonance_high_q_limit():
    c = ReadoutCircuit(1e-3, 10e-3, 0.0, 100e-12, math.inf, 0.0)
    f0, q = resonance(c)
    assert f0 == pytest.approx(1 / (2 * math.pi * math.sqrt(10e-3 * 100e-12)), rel=1e-12)
    assert q == pytest.approx(math.sqrt(10e-3 / 100e-12) / 1e-3, rel=1e-9)   # √(L/C)/R


@pytest.mark.parametrize("circuit", [PAPER, ReadoutCircuit(500.0, 5e-3, 20e-12, 1e-9,
                                                            2e3, 50e-12)])
def test_resonance_closed_form(circuit):
    _, w0, sig = second_order(circuit)
    f0, q = resonance(circuit)
    assert f0 == pytest.approx(w0 / (2 * math.pi), rel=1e-10)
    assert q == pytest.approx(w0 / (2 * sig), rel=1e-10)


@pytest.mark.parametrize("q_target", [2.0, 5.0, 50.0])
def test_peak_gain_closed_form(q_target):
    """Series RLC into a capacitor: |H| peaks at ω0 √(1 − 1/(2Q²)) with Q/√(1 − 1/(4Q²));
    a coil impedance given as the callable R + jωL is the same circuit."""
    ind, cap = 10e-3, 1e-9
    r = math.sqrt(ind / cap) / q_target
    c = ReadoutCircuit(r, ind, 0.0, cap, math.inf, 0.0)
    f0 = 1 / (2 * math.pi * math.sqrt(ind * cap))
    f_peak, gain = peak_gain(c)
    assert f_peak == pytest.approx(f0 * math.sqrt(1 - 0.5 / q_target**2), rel=1e-7)
    assert gain == pytest.approx(q_target / math.sqrt(1 - 0.25 / q_target**2), rel=1e-9)
    same = peak_gain(c, lambda f: r + 2j * np.pi * f * ind)
    assert same == pytest.approx((f_peak, gain), rel=1e-12)
    # a lossier coil at high frequency (eddy losses: R grows with f) lowers the peak
    lossy = peak_gain(c, lambda f: r * (1 + (f / f0) ** 2) + 2j * np.pi * f * ind)
    assert lossy[1] < gain


def test_peak_gain_refuses_a_bad_band():
    with pytest.raises(InputError, match="band"):
        peak_gain(PAPER, band=(1e5, 1e3))


@pytest.mark.parametrize("q_target", [0.3, 1 / math.sqrt(2), 5.0, 50.0])
def test_bandwidth_closed_form(q_target):
    # series RLC into an open input: ω0 = 1/√(LC), Q = √(L/C)/R
    ind, cap = 10e-3, 1e-9
    c = ReadoutCircuit(math.sqrt(ind / cap) / q_target, ind, 0.0, cap, math.inf, 0.0)
    f0, q = resonance(c)
    x = 1 - 1 / (2 * q**2)
    expected = f0 * math.sqrt(x + math.sqrt(x**2 + 1))
    assert bandwidth(c) == pytest.approx(expected, rel=1e-9)
    if q_target == 1 / math.sqrt(2):
        assert bandwidth(c) == pytest.approx(f0, rel=1e-9)       # Butterworth


def test_resonance_figures_equal_the_poles_and_the_search():
    """The closed forms against the general route: eigenvalues of the state matrix for f0,
    Q and the slowest decay, the grid-and-Brent search for the bandwidth (under-, critically
    and overdamped circuits, finite and open inputs), vectorised in one call."""
    rng = np.random.default_rng(5)
    circuits = [ReadoutCircuit(r, ind, c_w, 100e-12, r_in, 20e-12)
                for r, ind, c_w, r_in in zip(rng.uniform(5.0, 500.0, 12),
                                             rng.uniform(1e-3, 50e-3, 12),
                                             rng.uniform(1e-12, 30e-12, 12),
                                             [1e6, math.inf, 1e3, 1e4] * 3, strict=True)]
    circuits.append(ReadoutCircuit(2e4, 1e-3, 0.0, 1e-9, math.inf, 0.0))  # Q = 0.05
    circuits.append(ReadoutCircuit(2 * math.sqrt(1e-3 / 1e-9), 1e-3, 0.0, 1e-9, math.inf,
                                   0.0))  # critically damped
    fig = resonance_figures([c.resistance for c in circuits],
                            [c.inductance for c in circuits],
                            [c.total_capacitance for c in circuits],
                            [0.0 if math.isinf(c.input_resistance) else 1 / c.input_resistance
                             for c in circuits])
    for k, c in enumerate(circuits):
        p = np.linalg.eigvals(state_space(c)[0])
        omega0 = math.sqrt(abs((p[0] * p[1]).real))
        assert fig.resonance_hz[k] == pytest.approx(omega0 / (2 * math.pi), rel=1e-9)
        assert fig.quality_factor[k] == pytest.approx(omega0 / -(p[0] + p[1]).real, rel=1e-9)
        assert fig.decay_s[k] == pytest.approx(1 / np.min(-p.real), rel=1e-6)
        assert fig.bandwidth_hz[k] == pytest.approx(_bandwidth_search(c), rel=1e-9)
        assert (resonance(c), bandwidth(c)) == ((fig.resonance_hz[k], fig.quality_factor[k]),
                                                fig.bandwidth_hz[k])
    # with a cable resistance the search stays the route, near the R_c = 0 value
    assert bandwidth(WITH_CABLE_R) == pytest.approx(bandwidth(PAPER), rel=0.05)
    with pytest.raises(InputError, match="inductance > 0"):
        resonance_figures(50.0, 0.0, 1e-10, 0.0)


# ---------------------------------------------------------------- time domain

@pytest.mark.parametrize("daq_rate", [1e7, 3.3e6])
def test_step_response_matches_closed_form(daq_rate):
    # EMF rises linearly over one EMF sample (a step up to the hold's resolution) then
    # holds: y = (E/Tr)[r(t) − r(t − Tr)] exactly for the piecewise-linear EMF.
    dt, e0 = 1e-7, 2.0
    t = np.arange(-20, 3000) * dt
    emf = np.where(t > 0, e0, 0.0)
    td, v = daq_voltage(PAPER, t, emf, daq_rate)
    expected = e0 / dt * (ramp_response(PAPER, td) - ramp_response(PAPER, td - dt))
    assert td[1] - td[0] == pytest.approx(1 / daq_rate)
    np.testing.assert_allclose(v, expected, rtol=0, atol=1e-10 * e0)


def test_impulse_response_converges_second_order():
    # Triangular EMF pulse of area 1 and half-width w → impulse response as w → 0, O(w²).
    errors = []
    for w in (2e-6, 1e-6, 5e-7):
        dt = w / 4
        t = np.arange(-8, int(4e-4 / dt)) * dt
        emf = np.clip(1 - np.abs(t - 2 * w) / w, 0, None) / w
        td, v = daq_voltage(PAPER, t, emf, 1e7)
        late = td > 4 * w
        exact = impulse_response(PAPER, td[late] - 2 * w)
        errors.append(np.max(np.abs(v[late] - exact)) / np.max(np.abs(exact)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.9), (errors, orders)


@pytest.mark.parametrize("freq", [1e3, 2e4, 9e4, 3e5])
def test_sine_steady_state_matches_transfer_function(freq):
    c = ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 3e4, 20e-12)   # damped: Q ≈ 1.3
    dt = 1 / (freq * 400)
    n = math.ceil(max(30 / freq, 400e-6) / dt)
    t = np.arange(n) * dt
    emf = np.sin(2 * np.pi * freq * t)
    td, v = daq_voltage(c, t, emf, 1 / (5 * dt))
    h = transfer_function(c, [freq])[0]
    steady = td > td[-1] - 5 / freq
    expected = np.abs(h) * np.sin(2 * np.pi * freq * td[steady] + np.angle(h))
    # piecewise-linear EMF: error ~ (ω dt)²/12 of the amplitude
    np.testing.assert_allclose(v[steady], expected, atol=3e-5 * max(abs(h), 1e-3))
    # and identical to scipy's lsim on the same (linear-hold) input
    a, b, cc = state_space(c)
    _, y_ref, _ = signal.lsim((a, b[:, :1], cc[None, :], [[0.0]]), emf, t, interp=True)
    np.testing.assert_allclose(v, y_ref[::5][: v.size], atol=1e-9 * max(abs(h), 1e-3))


def test_dc_initial_state():
    t = np.arange(100) * 1e-7
    _, v = daq_voltage(PAPER, t, np.full(100, 3.0), 1e7)
    np.testing.assert_allclose(v, 3.0 * transfer_function(PAPER, [0.0])[0].real, rtol=1e-12)


# ---------------------------------------------------------------- noise

def test_johnson_noise_of_pure_resistor():
    resistor = ReadoutCircuit(1e3, 0.0, 0.0, 0.0, math.inf, 0.0)
    band = (1e3, 1e6)
    assert noise_rms(resistor, NoiseModel(T_ROOM), band) == pytest.approx(
        math.sqrt(4 * K_B * T_ROOM * 1e3 * (band[1] - band[0])), rel=1e-10)


@pytest.mark.parametrize("circuit,cap", [
    (PAPER, PAPER.total_capacitance),
    (WITH_CABLE_R, WITH_CABLE_R.load_capacitance),
])
def test_thermal_noise_total_is_equipartition(circuit, cap):
    # All resistors at T: every energy store holds ½ kT, so the Lyapunov solution is
    # kT diag(1/L, 1/C...) and the DAQ node's ⟨v²⟩ = kT / C, the closed form noise_rms uses.
    p = thermal_covariance(circuit, T_ROOM)
    expected = np.diag([1 / circuit.inductance]
                       + ([1 / circuit.winding_capacitance] if circuit.cable_resistance else [])
                       + [1 / cap]) * K_B * T_ROOM
    # (the Lyapunov solve of the stiff third-order circuit is good to ~1e-9)
    np.testing.assert_allclose(p, expected, rtol=1e-8, atol=1e-9 * np.max(np.abs(expected)))
    assert noise_rms(circuit, NoiseModel(T_ROOM)) == pytest.approx(
        math.sqrt(K_B * T_ROOM / cap), rel=1e-12)
    np.testing.assert_allclose(total_noise_rms(np.array([cap, 2 * cap]), NoiseModel(T_ROOM)),
                               np.sqrt(K_B * T_ROOM / np.array([cap, 2 * cap])), rtol=1e-14)


@pytest.mark.parametrize("circuit", [PAPER, WITH_CABLE_R])
def test_psd_integral_matches_lyapunov(circuit):
    nm = NoiseModel(T_ROOM)
    assert noise_rms(circuit, nm, 1e13) == pytest.approx(noise_rms(circuit, nm), rel=1e-4)


def test_psd_at_dc_is_thevenin_resistance():
    # at DC the DAQ sees R + R_c in parallel with R_in
    c = WITH_CABLE_R
    r_th = 1 / (1 / (c.resistance + c.cable_resistance) + 1 / c.input_resistance)
    assert thermal_noise_psd(c, T_ROOM, [0.0])[0] == pytest.approx(4 * K_B * T_ROOM * r_th,
                                                                   rel=1e-12)


@pytest.mark.parametrize("circuit,rate", [
    (ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 3e4, 20e-12), 1e6),
    (ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 3e4, 20e-12, cable_resistance=1e3), 1e6),
])
def test_noise_realisation_variance_matches_psd_integral(circuit, rate):
    n = 200_000
    nm = NoiseModel(T_ROOM)
    t = np.arange(n) / rate
    _, v = daq_voltage(circuit, t, np.zeros(n), rate, noise=nm, rng=np.random.default_rng(7))
    expected = noise_rms(circuit, nm, 1e13) ** 2          # frequency-domain integral
    # samples are correlated over ~1/σ; the std. error is ~0.5 % (8 seeds), assert 3 %
    assert np.var(v) == pytest.approx(expected, rel=0.03)
    assert abs(np.mean(v)) < 5 * math.sqrt(expected * 200 / n)


def test_psd_with_the_coil_impedance_given_as_r_plus_sl_is_the_default():
    f = np.geomspace(1.0, 1e7, 200)
    z = PAPER.resistance + 2j * np.pi * f * PAPER.inductance
    np.testing.assert_allclose(thermal_noise_psd(WITH_CABLE_R, T_ROOM, f, coil_impedance=z),
                               thermal_noise_psd(WITH_CABLE_R, T_ROOM, f), rtol=1e-13)


def _lossy(f):
    """A coil whose loss grows with frequency, as with eddy currents: R + (sL ∥ R_e), the
    inductance shunted by a loss resistance (corner at 100 kHz)."""
    s = 2j * np.pi * np.asarray(f, dtype=float)
    r_e = 2 * np.pi * 1e5 * PAPER.inductance
    return PAPER.resistance + s * PAPER.inductance * r_e / (s * PAPER.inductance + r_e)


@pytest.mark.parametrize("impedance", [None, _lossy])
def test_spectral_noise_variance_matches_psd_integral(impedance):
    """Frequency-domain synthesis (used with Z(f)) has the variance ∫S df; for R + sL it
    equals the exact state-space (Lyapunov) variance."""
    rate, n = 2e6, 100_000
    nm = NoiseModel(T_ROOM)
    z = (lambda f: PAPER.resistance + 2j * np.pi * f * PAPER.inductance) if impedance is None \
        else impedance
    samples = np.concatenate([
        add_readout_noise(np.zeros(n), PAPER, nm, rate, rng=seed, coil_impedance=z)
        for seed in range(8)])
    f = np.linspace(0.0, rate / 2, 400_001)
    expected = np.trapezoid(thermal_noise_psd(PAPER, T_ROOM, f, coil_impedance=z(f)), f)
    # 8 × 1e5 samples correlated over ~2 Q / ω0 (≈ 100 samples): std. error ~1 %, assert 4 %
    assert np.var(samples) == pytest.approx(expected, rel=0.04)
    if impedance is None:
        assert expected == pytest.approx(noise_rms(PAPER, nm) ** 2, rel=2e-3)
    else:  # the loss changes the spectrum: more noise above the corner, less at resonance
        f_hi = np.array([3e5])
        assert thermal_noise_psd(PAPER, T_ROOM, f_hi, coil_impedance=z(f_hi))[0] > \
            thermal_noise_psd(PAPER, T_ROOM, f_hi)[0]
        k = int(np.argmax(thermal_noise_psd(PAPER, T_ROOM, f)))
        assert thermal_noise_psd(PAPER, T_ROOM, f[k:k + 1], coil_impedance=z(f[k:k + 1]))[0] < \
            thermal_noise_psd(PAPER, T_ROOM, f[k:k + 1])[0]


def test_daq_noise_and_quantisation():
    rate, n = 1e6, 100_000
    nm = NoiseModel(T_ROOM, adc_bits=12, adc_range_V=2e-3, input_noise_V_per_rtHz=20e-9)
    circuit = ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 3e4, 20e-12)
    t = np.arange(n) / rate
    _, v = daq_voltage(circuit, t, np.zeros(n), rate, noise=nm, rng=3)
    lsb = 2e-3 / 4096
    np.testing.assert_allclose(v / lsb, np.round(v / lsb), atol=1e-9)
    expected = noise_rms(circuit, nm, sample_rate=rate)
    assert expected > 5 * lsb                       # noise spans many codes
    assert np.std(v) == pytest.approx(expected, rel=0.03)


def test_noise_is_seeded_and_clipped():
    t = np.arange(2000) * 1e-7
    nm = NoiseModel(T_ROOM, adc_bits=8, adc_range_V=1.0)
    emf = 5.0 * np.sin(2 * np.pi * 5e3 * t)
    _, a = daq_voltage(PAPER, t, emf, 1e7, noise=nm, rng=11)
    _, b = daq_voltage(PAPER, t, emf, 1e7, noise=nm, rng=11)
    _, c = daq_voltage(PAPER, t, emf, 1e7, noise=NoiseModel(T_ROOM), rng=12)
    _, d = daq_voltage(PAPER, t, emf, 1e7, noise=NoiseModel(T_ROOM), rng=13)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(c, d)
    assert a.max() == pytest.approx(0.5 - 1 / 256) and a.min() == pytest.approx(-0.5)


def test_noise_rms_band_parts():
    nm = NoiseModel(0.0, 12, 2e-3, 20e-9)
    rate = 1e6
    full = noise_rms(PAPER, nm, sample_rate=rate)
    band = noise_rms(PAPER, nm, 1e5, sample_rate=rate)
    lsb = 2e-3 / 4096
    assert full == pytest.approx(math.sqrt((20e-9) ** 2 * rate / 2 + lsb**2 / 12))
    assert band == pytest.approx(full * math.sqrt(1e5 / (rate / 2)))


@pytest.mark.parametrize("call,match", [
    (lambda: ReadoutCircuit(0.0, 1e-3, 0, 0, 1e6, 0), "resistance"),
    (lambda: ReadoutCircuit(1.0, 1e-3, -1e-12, 0, 1e6, 0), "winding_capacitance"),
    (lambda: ReadoutCircuit(1.0, 1e-3, 0, 0, 0.0, 0), "input_resistance"),
    (lambda: daq_voltage(ReadoutCircuit(1.0, 0.0, 0, 1e-12, 1e6, 0), [0, 1], [0, 0], 1.0),
     "inductance"),
    (lambda: daq_voltage(PAPER, [0.0, 1.0, 3.0], [0, 0, 0], 1.0), "uniformly"),
    (lambda: daq_voltage(PAPER, [0.0, 1.0], [0.0], 1.0), "equal length"),
    (lambda: daq_voltage(PAPER, [0.0, 1.0], [0.0, 1.0], -1.0), "sample_rate"),
    (lambda: NoiseModel(adc_bits=12), "adc_range_V"),
    (lambda: noise_rms(PAPER, NoiseModel(adc_bits=12, adc_range_V=1.0)), "sample_rate"),
    (lambda: noise_rms(PAPER, NoiseModel(), (5.0, 1.0)), "bandwidth"),
])
def test_bad_input_raises(call, match):
    with pytest.raises(InputError, match=match):
        call()
