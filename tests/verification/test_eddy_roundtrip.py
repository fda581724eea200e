"""The main study with eddy currents end to end: synth -> compare -> diagnose, and a hidden
cable found, through the command line (slow: the eddy-current model of ``paper-mss`` is
committed in ``meshes/``, the diagnosis runs the chain a few hundred times).
"""

from __future__ import annotations

import json

import pytest

from msens.cli import main
from msens.config.study import default_study_path, load_study
from msens.diagnose.effects import Context
from msens.diagnose.hidden import hidden_case
from msens.diagnose.predict import Predictor, baseline_state
from msens.diagnose.workflow import baseline_dissipation
from msens.io.read import write_waveform
from msens.pipeline import output_times
from msens.synth import RigEffects

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def study_file(tmp_path_factory):
    text = default_study_path().read_text()
    at = text.index("[electronics]")
    path = tmp_path_factory.mktemp("eddy") / "paper-eddy.toml"
    path.write_text(text[:at] + "[field]\neddy_currents = true\n\n" + text[at:])
    return path


def test_synth_compare_diagnose_on_the_main_study_with_eddy_currents(study_file, tmp_path):
    data = tmp_path / "shots.csv"
    assert main(["synth", str(study_file), "--out", str(data), "--shots", "2", "--noise",
                 "0.01", "--seed", "11"]) == 0
    assert main(["compare", str(study_file), str(data), "--out", str(tmp_path / "cmp")]) == 0
    report = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    for ch in report["channels"]:
        m, model = ch["measured"], ch["model"]
        assert abs(m["tof_us"]["mean"] - model["tof_us"]) < 0.5
        assert abs(m["ar"]["mean"] - model["ar"]) < 0.01
        assert m["correlation"]["mean"] >= 0.99
    out = tmp_path / "diag"
    assert main(["diagnose", str(data), "--study", str(study_file), "--out", str(out)]) == 0
    first = json.loads((out / "diagnosis.json").read_text())["passes"][0]
    assert first["effect"] == "none", first


def test_diagnose_names_a_hidden_cable_with_eddy_currents(study_file, tmp_path):
    study = load_study(study_file)
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    wf, truth = hidden_case(ctx, base, Predictor(output_times(study)), seed=3,
                            draw_effects=("cable_capacitance",),
                            rig=RigEffects(seed=3, noise=0.01))
    path = tmp_path / "cable.csv"
    write_waveform(wf, path)
    out = tmp_path / "d"
    assert main(["diagnose", str(path), "--study", str(study_file), "--out", str(out)]) == 0
    first = json.loads((out / "diagnosis.json").read_text())["passes"][0]
    assert first["effect"] == "cable_capacitance"
    c = truth["cable_capacitance"]["cable_capacitance_f"]
    assert first["parameters"]["cable_capacitance_f"] == pytest.approx(c, rel=0.1)
