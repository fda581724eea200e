"""One gain convention across the commands: synth's true gain is what compare and diagnose
report (measured = gain x model)."""

from __future__ import annotations

import json

import pytest

from msens.cli import main
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, load_study
from msens.diagnose import diagnose
from msens.io.read import read_waveform
from msens.synth import GAIN_CONVENTION, GAIN_CONVENTION_KEY, GAIN_KEY, truth_gain_key


def test_synth_gain_is_what_compare_and_diagnose_report(tmp_path):
    shots = tmp_path / "shots.csv"
    assert main(["synth", PAPER_TABLE2, "--setup", "bead", "--shots", "2", "--seed", "5",
                 "--out", str(shots)]) == 0
    wf = read_waveform(shots)
    assert wf.metadata[GAIN_CONVENTION_KEY] == GAIN_CONVENTION
    truth = {f"bead@{p}": float(wf.metadata[truth_gain_key("bead", p)]) for p in (13, 18)}
    assert main(["compare", PAPER_TABLE2, str(shots), "--out",
                 str(tmp_path / "cmp")]) == 0
    report = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    assert GAIN_KEY in report["gain_convention"]
    for ch in report["channels"]:
        got = ch["measured"][GAIN_KEY]["mean"]
        assert got == pytest.approx(truth[ch["channel"]], rel=0.01)
        assert ch[f"{GAIN_KEY}_unit"] == "V/N"
        assert ch["measured"]["conversion_factor_K"]["mean"] == pytest.approx(1.0 / got,
                                                                              rel=1e-3)
    # diagnose on the same file (its baseline is msens run's, with the study's Eq. 10
    # dissipation): the baseline is the truth, its gains are synth's
    d = diagnose(wf, load_study(builtin_study_path(PAPER_TABLE2)), effects=["striker_velocity"])
    cal = d.to_json()["record_calibration"]
    assert cal["convention"].startswith(GAIN_CONVENTION)
    for ch in cal["channels"]:
        assert ch[GAIN_KEY] == pytest.approx(truth[ch["channel"]], rel=0.01)
        assert ch[f"{GAIN_KEY}_unit"] == "V/N"
