"""Fixtures shared by the diagnosis tests."""

from __future__ import annotations

import pytest

from msens.config.study import default_study_path, load_study
from msens.diagnose.effects import Context
from msens.diagnose.predict import Predictor, baseline_state, setup_result
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import output_times


@pytest.fixture(scope="module")
def mss():
    """The main study's physics MsS setup: (context, baseline state, predictor, baseline
    result, baseline records (sensors, nt) in V)."""
    study = load_study(default_study_path())
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    predictor = Predictor(output_times(study))
    return ctx, base, predictor, setup_result(ctx, base, predictor), \
        predictor.records([base])[0]
