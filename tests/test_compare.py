"""Synthetic measurements and predicted-vs-measured comparison (paper Eq. 11)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from msens import api
from msens.cli import main
from msens.compare import compare
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path
from msens.errors import InputError
from msens.io.read import read_waveform
from msens.io.waveform import Channel, Waveform
from msens.synth import RigEffects, synthesize, truth_gain_key


@pytest.fixture(scope="module")
def result():
    study = api.load_paper_table2()
    return api.run(study)


def _setup(result, name):
    return next(s for s in result.setups if s.setup.name == name)


@pytest.mark.parametrize("name", ["bead", "rod", "mss"])
def test_self_comparison_has_zero_error(result, name):
    clean = RigEffects(noise=0.0, offset=0.0, jitter_s=0.0)
    report = compare(result, synthesize(_setup(result, name), clean))
    for ch in report["channels"]:
        m = ch["measured"]
        # not exactly 0: synth shifts records by a fraction of a sample (linear interpolation)
        assert m["nrmse"]["mean"] < 5e-4
        assert m["correlation"]["mean"] > 1 - 1e-6
        assert m["tof_us"]["mean"] == pytest.approx(ch["model"]["tof_us"], abs=0.01)
        assert m["ar"]["mean"] == pytest.approx(ch["model"]["ar"], abs=1e-4)


@pytest.mark.parametrize("name", ["bead", "rod", "mss"])
def test_eq11_factor_recovers_known_gain(result, name):
    """Noisy shots (1% noise, offsets, jitter): the gain is synth's true gain within 1 %
    (one convention: measured = gain x model), and K is its inverse."""
    waveform = synthesize(_setup(result, name), RigEffects(shots=5, noise=0.01, seed=7))
    report = compare(result, waveform)
    assert report["gain_convention"].startswith("measured = gain x model")
    for ch in report["channels"]:
        truth = float(waveform.metadata[truth_gain_key(ch["kind"], ch["particle"])])
        gain = ch["measured"]["gain_measured_per_model"]["mean"]
        assert gain == pytest.approx(truth, rel=0.01)
        assert ch["measured"]["conversion_factor_K"]["mean"] * truth == pytest.approx(
            1.0, abs=0.01)


def test_synth_is_reproducible(result):
    a = synthesize(_setup(result, "bead"), RigEffects(shots=2, seed=3))
    b = synthesize(_setup(result, "bead"), RigEffects(shots=2, seed=3))
    c = synthesize(_setup(result, "bead"), RigEffects(shots=2, seed=4))
    assert a == b
    assert not np.array_equal(a.data, c.data)


def test_study_not_matching_data(result):
    w = Waveform(time=np.arange(100) * 1e-7, data=np.zeros((100, 1)),
                 channels=(Channel("bead", 7),))
    with pytest.raises(InputError, match="does not match the data's sensors"):
        compare(result, w)


def test_cli_synth_compare_roundtrip(tmp_path):
    data = tmp_path / "shots.npz"
    study = str(builtin_study_path(PAPER_TABLE2))
    assert main(["synth", study, "--out", str(data), "--setup", "rod", "--shots", "2"]) == 0
    assert read_waveform(data).metadata["synthetic"] == "true"
    assert main(["synth", study, "--out", str(data)]) == 2  # never overwrites
    out = tmp_path / "cmp"
    assert main(["compare", study, str(data), "--out", str(out)]) == 0
    report = json.loads((out / "compare.json").read_text())
    assert report["setup"] == "rod" and report["shots"] == 2
    assert (out / "overlay.png").stat().st_size > 10_000


def test_cli_bad_setup_exit_2(tmp_path, capsys):
    code = main(["synth", str(builtin_study_path(PAPER_TABLE2)), "--out", str(tmp_path / "x.csv"),
                 "--setup", "laser"])
    assert code == 2
    assert "--setup must be one of" in capsys.readouterr().err


def test_channel_without_sensor_is_named(result):
    w = Waveform(time=np.arange(100) * 1e-7, data=np.zeros((100, 2)),
                 channels=(Channel("bead", 13), Channel("mss", 7)))
    with pytest.raises(InputError, match=r"channel\(s\) mss@7 of the data have no sensor in "
                                         r"study 'paper-table2'.*bead \(bead@13, bead@18\)"):
        compare(result, w)


@pytest.mark.parametrize(("name", "unit", "gain_unit"),
                         [("bead", "N/V", "V/N"), ("mss", "N/(V s)", "V/(N/s)")])
def test_gain_unit_and_truncated_record(result, name, unit, gain_unit):
    waveform = synthesize(_setup(result, name), RigEffects(seed=2))
    ch = compare(result, waveform)["channels"][0]
    assert ch["K_unit"] == unit
    assert ch["gain_measured_per_model_unit"] == gain_unit
    cut = Waveform(waveform.time[:2500], waveform.data[:2500], waveform.channels)
    with pytest.raises(InputError, match="no reflected pulse in the record"):
        compare(result, cut)


@pytest.mark.parametrize("unit", ["N/V", "N/(V s)", "V/V"])
def test_format_comparison_shows_gain_unit(unit):
    stat = {"mean": 1.5, "std": 0.0}
    report = {"setup": "s", "shots": 1, "channels": [{
        "channel": "mss@13", "K_unit": unit, "model": {"tof_us": 288.0, "ar": 0.7},
        "measured": {k: stat for k in ("conversion_factor_K", "tof_us", "ar", "nrmse",
                                       "correlation")}}]}
    row = api.format_comparison(report).splitlines()[3]
    assert row.startswith(f"mss@13     {1.5:>10} {unit:<7} ")
