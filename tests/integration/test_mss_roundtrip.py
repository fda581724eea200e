"""The main study end to end across the commands: synth -> compare -> diagnose on physics
MsS data (``studies/paper-mss.toml``), through the command line as a user runs it.

Synthetic data: two shots with an unknown amplifier gain, offset, trigger delay and 1 % noise.
compare must recover the model's TOF (0.5 µs), AR (0.01) and shape (correlation 0.99);
diagnose must find nothing missing in undisturbed data, and name a longer cable when the data
hide one (its capacitance within 10 %).
"""

from __future__ import annotations

import json

import pytest

from msens.cli import main
from msens.config.study import default_study_path, load_study
from msens.diagnose.effects import Context
from msens.diagnose.hidden import hidden_case, parameters_recovered
from msens.diagnose.predict import Predictor, baseline_state
from msens.diagnose.workflow import baseline_dissipation
from msens.io.read import write_waveform
from msens.pipeline import output_times
from msens.synth import RigEffects

STUDY = str(default_study_path())


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    path = tmp_path_factory.mktemp("mss") / "shots.csv"
    args = ["synth", STUDY, "--out", str(path), "--shots", "2", "--noise", "0.01",
            "--seed", "7"]
    assert main(args) == 0
    return path


def test_compare_recovers_the_model_on_its_own_mss_data(data, tmp_path):
    assert main(["compare", STUDY, str(data), "--out", str(tmp_path / "cmp")]) == 0
    report = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    assert report["shots"] == 2
    for ch in report["channels"]:
        m, model = ch["measured"], ch["model"]
        assert ch["kind"] == "mss"
        assert abs(m["tof_us"]["mean"] - model["tof_us"]) < 0.5
        assert abs(m["ar"]["mean"] - model["ar"]) < 0.01
        assert m["correlation"]["mean"] >= 0.99


@pytest.mark.slow
def test_diagnose_finds_nothing_missing_in_undisturbed_mss_data(data, tmp_path):
    """Slow group (~90 s, the whole library searched on the main study: the default suite
    ran over its 10 min). The default suite keeps diagnose's `none` on bead data
    (tests/diagnose); on physics-MsS data it is checked here and on the eddy-current main
    study (tests/verification/test_eddy_roundtrip.py), both in the slow group."""
    out = tmp_path / "diag"
    assert main(["diagnose", str(data), "--study", STUDY, "--out", str(out)]) == 0
    report = json.loads((out / "diagnosis.json").read_text())
    first = report["passes"][0] if "passes" in report else report
    assert first["effect"] == "none", first["candidates"][:3]
    assert first["misfit_before"] < 1.5


def diagnose_hidden(study_path, tmp_path, effect: str, seed: int = 3) -> dict:
    """Data of ``study_path`` with one ``effect`` hidden in them (drawn as the acceptance set
    draws it, 1 % noise): diagnose names the effect and recovers its parameters within 10 %
    (also run on the eddy-current main study). Returns the first pass."""
    study = load_study(study_path)
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    wf, truth = hidden_case(ctx, base, Predictor(output_times(study)), seed=seed,
                            draw_effects=(effect,), rig=RigEffects(seed=seed, noise=0.01))
    path = tmp_path / f"{effect}.csv"
    write_waveform(wf, path)
    out = tmp_path / "d"
    assert main(["diagnose", str(path), "--study", str(study_path), "--out", str(out)]) == 0
    first = json.loads((out / "diagnosis.json").read_text())["passes"][0]
    assert first["effect"] == effect, (first["effect"], truth)
    assert parameters_recovered(first["parameters"], truth[effect], 0.1), (
        first["parameters"], truth[effect])
    return first


@pytest.mark.slow
def test_diagnose_names_a_hidden_cable_on_mss_data(tmp_path):
    """A whole diagnosis (~70 s on 2 cores): in the slow group, which also runs it on the
    eddy-current study (tests/verification/test_eddy_roundtrip.py); the default suite keeps
    the undisturbed round trip."""
    diagnose_hidden(default_study_path(), tmp_path, "cable_capacitance")
