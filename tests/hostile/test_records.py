"""Measured records that carry no comparable signal: refused by compare and diagnose alike,
naming the file and channel (issue 24: confident nonsense)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from tests.hostile.conftest import TWENTY, assert_input_error, run_cli

from msens.io import Waveform, read_waveform, write_waveform
from msens.signals.signalcheck import orientation, pulse_width

STUDY = TWENTY


@pytest.fixture(scope="module")
def record(tmp_path_factory) -> tuple[Path, Waveform]:
    """The tiny study and two synthetic shots of it (noise 1 %)."""
    from msens import api

    d = tmp_path_factory.mktemp("rec")
    study = d / "tiny.toml"
    study.write_text(STUDY)
    path = api.synth(api.load(study), d / "w.csv", shots=2, noise=0.01, seed=1)
    return study, read_waveform(path)


def _write(tmp_path: Path, w: Waveform, time=None, data=None, channels=None) -> Path:
    out = tmp_path / "m.csv"
    write_waveform(Waveform(w.time if time is None else time,
                            w.data if data is None else data,
                            w.channels if channels is None else channels, w.metadata), out)
    return out


@pytest.mark.parametrize("command", ["compare", "diagnose"])
@pytest.mark.parametrize(("case", "fragments"), [
    ("inverted", ["looks inverted", "bead@10"]),
    ("time x2", ["time axis looks scaled", "bead@10"]),
    ("time x1000", ["time axis looks scaled"]),
    ("noise only", ["has no pulse"]),
    ("scaled 1e-300", ["peaks at", "scaling mistake"]),
    ("zeros", ["peaks at 0 V"]),
])
def test_record_refused(record, tmp_path, capsys, command, case, fragments):
    study, w = record
    data, time = w.data.copy(), w.time
    if case == "inverted":
        data = -data
    elif case == "time x2":
        time = 2.0 * time
    elif case == "time x1000":
        time = 1e3 * time
    elif case == "noise only":
        data = np.random.default_rng(0).normal(0.0, 1e-3, data.shape)
    elif case == "scaled 1e-300":
        data = data * 1e-300
    elif case == "zeros":
        data = np.zeros_like(data)
    path = _write(tmp_path, w, time=time, data=data)
    argv = (["compare", str(study), str(path)] if command == "compare"
            else ["diagnose", str(path), "--study", str(study)])
    code, err = run_cli([*argv, "--out", str(tmp_path / "o")], capsys, seconds=30)
    assert_input_error(code, err, "m.csv", *fragments)
    assert not any((tmp_path / "o").glob("*.json"))


@pytest.mark.parametrize("command", ["compare", "diagnose"])
def test_shot_missing_a_channel(record, tmp_path, capsys, command):
    """bead@10, bead@15#2 only: shot 2 lacks bead@10 (was a KeyError in diagnose)."""
    study, w = record
    keep = [i for i, c in enumerate(w.channels) if (c.repeat, c.particle) in ((1, 10), (2, 15))]
    path = _write(tmp_path, w, data=w.data[:, keep], channels=tuple(w.channels[i] for i in keep))
    argv = (["compare", str(study), str(path)] if command == "compare"
            else ["diagnose", str(path), "--study", str(study)])
    code, err = run_cli([*argv, "--out", str(tmp_path / "o")], capsys, seconds=30)
    assert_input_error(code, err, "m.csv", "shot #2", "same sensors")


def test_upright_record_passes_the_checks(record):
    """The checks' own measures on the synthetic record: upright, unscaled."""
    from msens import api
    from msens.compare import check_signal, match_setup

    study, w = record
    result = api.run(api.load(study))
    check_signal(match_setup(result, w), w, "w.csv")  # raises if it were refused


def test_measures_scale_and_sign():
    t = np.arange(2000) * 1e-7
    pulse = np.exp(-0.5 * ((t - 5e-5) / 5e-6) ** 2)
    width = pulse_width(pulse, 1e-7)
    assert width == pytest.approx(2.3548 * 5e-6, rel=0.02)  # FWHM of a Gaussian
    assert pulse_width(pulse, 2e-7) == pytest.approx(2 * width)
    bipolar = np.gradient(pulse)  # an MsS voltage: dF/dt
    assert orientation(bipolar, bipolar) < 1.0 < orientation(-bipolar, bipolar)
    assert orientation(pulse, pulse) < 1.0 < orientation(-pulse, pulse)
