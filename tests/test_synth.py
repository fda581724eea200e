"""Synthetic physics-MsS data (studies/paper-mss.toml) and its comparison with the model.

One run of the study serves every test: its coils' records are DAQ voltages in volts, which
synth writes at the model's scale times an amplifier gain of order 1 and compare aligns,
calibrates (V/V) and integrates like the model's own voltage.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from msens import api
from msens.compare import compare, model_record, processing_line
from msens.errors import InputError
from msens.io.read import read_waveform, write_waveform
from msens.io.waveform import Waveform
from msens.signals.features import FEATURE_CUTOFF_HZ, model_features
from msens.synth import UNITS, UNITS_KEY, RigEffects, synthesize, truth_gain_key

STUDY = Path(__file__).resolve().parents[1] / "studies" / "paper-mss.toml"


@pytest.fixture(scope="module")
def result():
    return api.run(api.load(STUDY))


@pytest.fixture(scope="module")
def setup(result):
    return result.setups[0]


def test_physics_mss_channel_is_model_volts_times_amplifier_gain(setup):
    effects = RigEffects(noise=0.0, offset=0.0, seed=2)
    waveform = synthesize(setup, effects)
    assert waveform.metadata[UNITS_KEY] == UNITS == "V"
    for s in setup.sensors:
        gain = float(waveform.metadata[truth_gain_key("mss", s.sensor.particle)])
        assert effects.gain_amplifier[0] <= gain <= effects.gain_amplifier[1]
        channel = waveform.channel(f"mss@{s.sensor.particle}")
        model_peak = float(np.max(np.abs(s.voltage_shape)))
        assert model_peak > 0.1  # volts: the model's prediction, not a shape
        # a sub-sample shift by linear interpolation lowers the peak by < 1e-3
        assert np.max(np.abs(channel)) == pytest.approx(gain * model_peak, rel=1e-3)


@pytest.mark.parametrize("suffix", [".csv", ".npz", ".tdms"])
def test_units_survive_file_round_trips(setup, tmp_path, suffix):
    waveform = synthesize(setup, RigEffects(shots=2, seed=1))
    back = read_waveform(write_waveform(waveform, tmp_path / f"w{suffix}"))
    assert back == waveform
    assert back.metadata[UNITS_KEY] == "V"


@pytest.mark.parametrize("seed", [0, 11, 3])
@pytest.mark.parametrize(("noise", "shots"), [(0.0, 1), (0.01, 5)])
def test_synth_compare_round_trip(result, setup, seed, noise, shots):
    """Measured: 0 noise: TOF, AR, gain exact to 1e-4; 1 % noise, 5 shots: TOF within
    0.06 us, AR 0.003, gain 0.07 %, speed 0.08 % (seeds 0..19)."""
    waveform = synthesize(setup, RigEffects(shots=shots, noise=noise, seed=seed))
    report = compare(result, waveform)
    assert report["shots"] == shots
    for ch in report["channels"]:
        model, measured = ch["model"], ch["measured"]
        truth = float(waveform.metadata[truth_gain_key(ch["kind"], ch["particle"])])
        assert ch["K_unit"] == ch["gain_measured_per_model_unit"] == "V/V"
        assert measured["tof_us"]["mean"] == pytest.approx(model["tof_us"], abs=0.5)
        assert measured["ar"]["mean"] == pytest.approx(model["ar"], abs=0.01)
        assert measured["correlation"]["mean"] >= 0.99
        assert measured["gain_measured_per_model"]["mean"] == pytest.approx(truth, rel=0.01)
    speed = report["speed"]
    assert speed["measured_m_per_s"]["mean"] == pytest.approx(speed["model_m_per_s"], rel=0.01)
    # the model's features are those of msens run, low-passed as the measured records
    assert speed["run_m_per_s"] == setup.speed_incident
    assert report["model_processing"]["lowpass_hz"] == FEATURE_CUTOFF_HZ


def test_run_and_compare_report_the_same_model_features(result, setup):
    """One feature pipeline: compare's model column is what msens run reports for the same
    study, up to the low-pass that compare names (its ``model_processing`` and table line);
    before, run read the coil's flux before the read-out circuit and compare the
    integrated DAQ voltage (coil 13, magnetostatic: TOF 287.1 against 287.8 us)."""
    clean = RigEffects(noise=0.0, offset=0.0, jitter_s=0.0)
    report = compare(result, synthesize(setup, clean))
    rows = {r["particle"]: r for r in result.rows()}
    t = setup.history.t
    for ch, sensor in zip(report["channels"], setup.sensors, strict=True):
        row = rows[ch["particle"]]
        assert ch["run"]["tof_us"] == row["tof_us"] and ch["run"]["ar"] == row["ar"]
        # the named difference: the 250 kHz zero-phase low-pass moves no TOF by 0.02 us
        assert ch["model"]["tof_us"] == pytest.approx(row["tof_us"], abs=0.02)
        assert ch["model"]["ar"] == pytest.approx(row["ar"], abs=1e-4)
        # without it, compare's model record gives run's features (V s against N: one scale)
        same = model_features(model_record(sensor, t), t)
        assert float(same.tof) * 1e6 == pytest.approx(row["tof_us"], abs=1e-9)
        assert float(same.ar) == pytest.approx(row["ar"], rel=1e-12)
        # and they are the DAQ's, not those of the flux before the read-out circuit (the
        # circuit moves the TOF by 0.23 us with eddy currents, 0.7 us magnetostatic)
        flux = model_features(sensor.mss.weighted_force, t)
        assert abs(float(flux.tof - same.tof)) > 1e-7
    speed = report["speed"]
    assert speed["run_m_per_s"] == rows[13]["speed_m_per_s"]
    assert speed["model_m_per_s"] == pytest.approx(speed["run_m_per_s"], rel=1e-4)
    assert processing_line(report) in api.format_comparison(report)
    assert "250 kHz" in processing_line(report)


def _with_data(waveform: Waveform, data: np.ndarray, n: int | None = None) -> Waveform:
    return Waveform(waveform.time[:n], data[:n], waveform.channels, waveform.metadata)


def test_record_without_pulse_is_an_input_error(result, setup):
    waveform = synthesize(setup, RigEffects(seed=1))
    dead = waveform.data.copy()
    dead[:, 1] = np.random.default_rng(0).normal(0.0, 0.01, dead.shape[0])
    with pytest.raises(InputError, match="mss@18: no pulse found"):
        compare(result, _with_data(waveform, dead))
    with pytest.raises(InputError, match="no pulse found"):
        compare(result, _with_data(waveform, np.zeros_like(dead)))


def test_record_ending_before_the_reflection_is_an_input_error(result, setup):
    waveform = synthesize(setup, RigEffects(seed=1))
    with pytest.raises(InputError, match="mss@13: no reflected pulse in the record"):
        compare(result, _with_data(waveform, waveform.data, 2500))


def test_data_in_other_units_is_an_input_error(result, setup):
    waveform = synthesize(setup, RigEffects(seed=1))
    meta = dict(waveform.metadata, units="mV")
    with pytest.raises(InputError, match="units: mV"):
        compare(result, Waveform(waveform.time, waveform.data, waveform.channels, meta))
