"""The naming rule of ``msens diagnose`` against the field model's own errors
(``benchmarks/diagnose_field_nulls.py``).

A null file whose records are moved by one joint, nonlinear draw of every field-model error
at the accuracy the likelihood states (1 %) holds nothing the model lacks beyond what the
likelihood allows for: the diagnosis must name nothing and call the file explained. The
benchmark runs twelve such files; this test runs two (about 1-2 min each).
"""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def world():
    from benchmarks.diagnose_field_nulls import null_world

    return null_world()


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1000, 1007])
def test_field_model_errors_alone_name_nothing(world, seed):
    from benchmarks.diagnose_field_nulls import null_file

    from msens.diagnose import diagnose

    study, *rest = world
    wf, size = null_file(*rest, seed)
    assert size > 0.02  # the draw moves the records by more than their noise (1 %)
    d = diagnose(wf, study)
    assert d.effect == "none"
    assert d.explained
    live = [c.score for c in d.candidates if c.plausible and c.significant]
    assert max(live, default=-np.inf) < d.threshold
