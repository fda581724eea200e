"""Issue 34's calibration acceptance: over 20 seeded synthetic cases (one shot and five
shots alternately, true drop height and contact damping drawn from their priors), each
input's 90 % credible interval holds the truth in at least 80 % of the cases, and every
calibration converged (split R-hat <= 1.05). About 10 minutes on 2 cores."""

from __future__ import annotations

import pytest
from benchmarks.calibrate_coverage import NAMES, main

from msens.uq.mcmc import RHAT_LIMIT

pytestmark = pytest.mark.slow


def test_credible_intervals_cover_the_truth():
    summary = main(["--cases", "20", "--steps", "800"])
    for name in NAMES:
        assert summary["coverage_90"][name] >= 0.8, (name, summary["coverage_90"])
    assert summary["max_rhat"] <= RHAT_LIMIT, summary["max_rhat"]
