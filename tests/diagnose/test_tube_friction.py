"""``tube_friction`` on physics-MsS data (the main study): named with its drag within 10 %.

Slow (a physics-MsS diagnosis runs the field model's transducer on every candidate: minutes).
The bead-data case and the null case are in test_diagnose_workflow.py."""

from __future__ import annotations

import pytest

from msens.config.study import default_study_path, load_study
from msens.diagnose import diagnose
from msens.diagnose.effects import Context
from msens.diagnose.hidden import hidden_case
from msens.diagnose.predict import Predictor, baseline_state
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import output_times


@pytest.mark.slow
def test_names_tube_friction_on_physics_mss_data():
    study = load_study(default_study_path())
    ctx = Context(study, study.setups[0])
    gc, gw = baseline_dissipation(study)
    base = baseline_state(ctx, gc, gw)
    truth = 0.2
    wf, _ = hidden_case(ctx, base, Predictor(output_times(study)),
                        {"tube_friction": {"tube_drag_n_s_per_m": truth}}, seed=23)
    d = diagnose(wf, study)
    assert d.effect == "tube_friction"
    assert d.parameters["tube_drag_n_s_per_m"] == pytest.approx(truth, rel=0.10)
