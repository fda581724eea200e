"""msens calibrate: the shared likelihood, the sampler's diagnostics, the files, bad input.

The coverage of its credible intervals over 20 seeded synthetic cases is the slow test
``test_calibration_slow.py`` (``benchmarks/calibrate_coverage.py``).
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from benchmarks.calibrate_coverage import INPUTS as COVERAGE_INPUTS
from benchmarks.calibrate_coverage import STUDY
from tests.hostile.conftest import assert_input_error

from msens import api
from msens.cli import main
from msens.io.read import read_waveform
from msens.uq.calibration import run_calibrate
from msens.uq.inputs import load_inputs
from msens.uq.mcmc import autocorr_time, split_rhat
from msens.uq.posterior import Coordinates, Likelihood, select

#: The coverage benchmark's priors and one more input held at nominal.
INPUTS = COVERAGE_INPUTS + """[[input]]
name = "chain.youngs_modulus_pa"
distribution = "uniform"
lower = 190e9
upper = 210e9
reason = "datasheet spread"
"""


@pytest.fixture
def twenty(tmp_path: Path):
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    inputs = tmp_path / "u.toml"
    inputs.write_text(INPUTS)
    return study, inputs


def test_split_rhat_is_one_for_agreeing_chains_and_large_for_stuck_ones():
    rng = np.random.default_rng(0)
    agree = rng.standard_normal((2000, 16, 2))
    assert np.all(np.abs(split_rhat(agree) - 1.0) < 0.01)
    stuck = agree + np.arange(16)[None, :, None]  # every walker around its own value
    assert np.all(split_rhat(stuck) > 2.0)
    drift = agree + np.linspace(0, 5, 2000)[:, None, None]  # not stationary: halves differ
    assert np.all(split_rhat(drift) > 1.1)


def test_autocorr_time_of_ar1_chains_and_of_a_parameter_that_never_moved():
    """AR(1) with coefficient rho has tau = (1 + rho) / (1 - rho); a parameter whose
    walkers never moved (every proposal of a short run rejected) has no tau: NaN, and no
    division warning (pytest turns warnings into errors)."""
    rng = np.random.default_rng(3)
    rho, steps, walkers = 0.8, 20_000, 8
    x = np.zeros((steps, walkers))
    for t in range(1, steps):
        x[t] = rho * x[t - 1] + rng.normal(size=walkers)
    chains = np.stack([x, np.full_like(x, 0.25)], axis=2)
    tau = autocorr_time(chains)
    assert tau[0] == pytest.approx((1 + rho) / (1 - rho), rel=0.15)
    assert np.isnan(tau[1])
    stuck_walker = chains.copy()
    stuck_walker[:, 0, 0] = 1.0  # one walker of a moving parameter stood still
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # emcee divided by that walker's zero variance
        assert np.isnan(autocorr_time(stuck_walker)[1])


def test_likelihood_is_diagnose_s(twenty, tmp_path):
    """At the nominal inputs the calibration's chi^2 is the one diagnose judges the baseline
    by (same objective, records from msens run's code path)."""
    from msens.diagnose.workflow import waveform_baseline

    study_file, inputs_file = twenty
    study = api.load(study_file)
    data = read_waveform(api.synth(study, tmp_path / "w.csv", noise=0.01, seed=2))
    base = waveform_baseline(data, study)
    inputs = load_inputs(inputs_file, study)
    coords = Coordinates.of(inputs, select(inputs, ["striker.drop_height_m"]))
    lik = Likelihood(study, inputs, base.ctx.setup, base.objective)
    chi2 = lik.chi2(coords.rows(coords.center[None]))[0]
    assert chi2 == pytest.approx(float(base.objective.rss(base.records).sum()), rel=1e-6)
    # a drop height 5 % off the nominal is far less likely
    assert lik.chi2(coords.rows(coords.center[None] * 1.05))[0] > chi2 + 100


def test_waveform_calibration_recovers_a_drop_height(twenty, tmp_path):
    """Data made with a 7.5 mm drop (nominal 7.2 mm): the posterior moves there and its
    90 % interval holds the truth; the files are strict JSON and the figures exist."""
    study_file, inputs_file = twenty
    study = api.load(study_file)
    truth = 7.5e-3
    data = api.synth(study.replace({"striker.drop_height_m": truth}), tmp_path / "w.csv",
                     noise=0.01, seed=4)
    res = run_calibrate(study, tmp_path / "cal", data=read_waveform(data), inputs=inputs_file,
                        params=["striker.drop_height_m"], walkers=8, steps=120, seed=1,
                        progress=False)
    (p,) = res.report["inputs"]
    lo, hi = p["credible_interval_90"]
    assert lo <= truth <= hi, (lo, hi)
    assert hi - lo < 0.1e-3  # the data pin it far below the prior's 1 mm
    assert p["rhat"] is not None and p["rhat"] < 1.2
    assert res.report["held_at_nominal"] == ["chain.gamma_contact_kg_per_s",
                                             "chain.youngs_modulus_pa"]
    text = (tmp_path / "cal" / "calibration.json").read_text()
    assert json.loads(text, parse_constant=lambda c: pytest.fail(c))["mode"] == "waveform"
    wf = res.report["predictive"]["waveform"]
    assert len(wf["channels"]) == 2 and len(wf["model_5_50_95"]) == 3
    for name in ("calibration_pairs.png", "calibration_predictive.png",
                 "calibration_trace.png"):
        assert (tmp_path / "cal" / name).stat().st_size > 10_000


def test_reference_rows_of_table2_from_the_command_line(tmp_path, capsys):
    """Calibrate on the bead rows of the paper's Table 2, predict the others (CLI)."""
    out = tmp_path / "cal"
    code = main(["-q", "calibrate", "--study", "paper-table2", "--reference", "bead",
                 "--param", "striker.drop_height_m", "--walkers", "8", "--steps", "30",
                 "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    report = json.loads((out / "calibration.json").read_text())
    refs = report["predictive"]["reference"]
    assert len(refs) == 6  # three setups x two sensors
    assert [r["calibrated_on"] for r in refs].count(True) == 2
    for r in refs:
        for f in ("tof_us", "ar"):
            q = r[f]["model_5_50_95"]
            assert q[0] <= q[1] <= q[2]
    printed = capsys.readouterr().out
    assert "striker.drop_height_m" in printed and "R-hat" in printed


@pytest.mark.parametrize("study, args, fragments", [
    ("paper-table2", ["--param", "chain.nonsense"], ["--param 'chain.nonsense'", "allowed:"]),
    ("paper-mss", ["--param", "sensor[1].coil.turns"], ["whole number", "allowed:"]),
    ("paper-mss", ["--param", "field.steel_conductivity_S_per_m"],
     ["held at its nominal value"]),
    ("paper-table2", ["--param", "striker.drop_height_m", "--param", "striker.drop_height_m"],
     ["more than once"]),
    ("paper-table2", ["--walkers", "7"], ["--walkers must be an even whole number"]),
    ("paper-table2", ["--steps", "5"], ["--steps must be a whole number from 20"]),
    ("paper-table2", ["--reference", "nosuch"], ["--reference must be one of"]),
])
def test_bad_input_is_refused_before_any_simulation(tmp_path, capsys, study, args, fragments):
    """Feature mode (the checks of the inputs come before those of the measurement)."""
    ref = [] if "--reference" in args else ["--reference", "bead"]
    argv = ["calibrate", "--study", study, *ref, *args, "--out", str(tmp_path / "o")]
    start = time.perf_counter()
    code = main(argv)
    assert time.perf_counter() - start < 20
    assert_input_error(code, capsys.readouterr().err, *fragments)
    assert not (tmp_path / "o" / "calibration.json").exists()


def test_data_of_another_setup_is_refused(twenty, tmp_path, capsys):
    study_file, inputs_file = twenty
    other = tmp_path / "other.toml"
    other.write_text(STUDY.replace("particle = 15", "particle = 16"))
    data = api.synth(api.load(other), tmp_path / "w.csv", noise=0.01, seed=1)
    code = main(["calibrate", str(data), "--study", str(study_file), "--inputs",
                 str(inputs_file), "--out", str(tmp_path / "o")])
    assert_input_error(code, capsys.readouterr().err, "does not match the data's sensors")
    assert not (tmp_path / "o" / "calibration.json").exists()


def test_data_and_reference_together_are_refused(twenty, tmp_path, capsys):
    study_file, _inputs_file = twenty
    data = api.synth(api.load(study_file), tmp_path / "w.csv", noise=0.01, seed=1)
    code = main(["calibrate", str(data), "--study", str(study_file), "--reference", "coverage",
                 "--out", str(tmp_path / "o")])
    assert_input_error(code, capsys.readouterr().err, "either DATA", "not both")
