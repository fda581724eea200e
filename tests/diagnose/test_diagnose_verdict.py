"""An honest verdict: fit-free noise, shot ensembles, physical ranges, "explained"."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from msens.calibrate import DissipationFit
from msens.config.assemble import precompression_forces
from msens.config.schema import PAPER_TABLE2, PrecompressionSpec
from msens.config.study import builtin_study_path, load_study
from msens.diagnose import diagnose
from msens.diagnose.effects import Context, get
from msens.diagnose.hidden import hidden_case, hidden_shots, outside_case
from msens.diagnose.noise import ensemble, shot_matrix
from msens.diagnose.predict import Predictor, baseline_state
from msens.diagnose.verdict import consistency_limit, verdict
from msens.errors import InputError
from msens.io.waveform import Channel, Waveform
from msens.pipeline import output_times
from msens.synth import RigEffects

GAMMA_C = 4.8


def _fit() -> DissipationFit:
    nan = math.nan
    return DissipationFit(gamma_c=GAMMA_C, gamma_w=0.0, objective=nan, ar_top_model=nan,
                          ar_bottom_model=nan, tof_top_model=nan, tof_bottom_model=nan,
                          n_simulations=0)


@pytest.fixture(scope="module")
def bench():
    study = load_study(builtin_study_path(PAPER_TABLE2))
    ctx = Context(study, study.setup("bead"))
    return study, ctx, baseline_state(ctx, GAMMA_C, 0.0), Predictor(output_times(study))


def _pulses(shifts, sigma, seed=0):
    rng = np.random.default_rng(seed)
    t = (np.arange(3000) - 300) * 1e-7
    cols, chans = [], []
    for k, s in enumerate(shifts):
        for j, (p, t0) in enumerate(((13, 60e-6), (18, 110e-6))):
            clean = np.exp(-((t - t0 - s * 1e-7) / 4e-6) ** 2) * (1.0 + j)
            cols.append(clean + 0.3 + rng.normal(0.0, sigma, t.size))
            chans.append(Channel("bead", p, k + 1))
    return Waveform(time=t, data=np.column_stack(cols), channels=tuple(chans))


def test_ensemble_aligns_the_shots_and_gives_the_noise_of_their_mean():
    wf = _pulses([0, 37, -12, 5], sigma=0.01)
    e = ensemble(wf, [("bead", 13), ("bead", 18)])
    np.testing.assert_array_equal(e.shifts, [0, 37, -12, 5])
    np.testing.assert_allclose(e.sigma_pretrigger, 0.01, rtol=0.1)
    # the noise of the mean of 4 shots: sigma^2 / 4 (the scatter estimate, never below the
    # pre-trigger one, is biased up by a few per cent)
    np.testing.assert_allclose(np.mean(e.var, axis=1), 0.01**2 / 4, rtol=0.15)
    assert abs(float(np.mean(e.y[:, :200]))) < 0.01  # offsets removed
    assert e.shots == 4 and e.dof > 0


def test_a_shot_lacking_a_channel_is_an_input_error():
    wf = _pulses([0, 3], sigma=0.01)
    keep = [j for j, c in enumerate(wf.channels) if (c.particle, c.repeat) != (18, 2)]
    lacking = Waveform(time=wf.time, data=wf.data[:, keep],
                       channels=tuple(wf.channels[j] for j in keep))
    with pytest.raises(InputError, match=r"shot #2 has no channel bead@18"):
        shot_matrix(lacking, [("bead", 13), ("bead", 18)])


def test_noise_alone_passes_the_consistency_test_at_the_stated_rate():
    # n residual samples of unit noise against a variance estimated from m pre-trigger
    # samples: the limit is exceeded with probability alpha
    rng = np.random.default_rng(5)
    n, m, alpha, trials = 400, 150, 0.02, 4000
    limit = consistency_limit(n, m - 1, alpha)
    var_hat = rng.chisquare(m - 1, trials) / (m - 1)
    chi = rng.chisquare(n, trials) / n / var_hat
    assert np.mean(chi > limit) == pytest.approx(alpha, abs=0.008)
    # a known variance (infinite dof) is the chi-square quantile
    assert consistency_limit(n, math.inf, alpha) < limit


def test_the_verdict_says_where_the_residual_sits():
    rows = [{"channel": "bead@13", "window": w, "n_samples": 300,
             "chi2_per_sample_after": x} for w, x in (("incident", 1.0), ("reflected", 6.0))]
    v = verdict(300 * 7.0, 600, rows, dof=199)
    assert not v["explained"]
    assert v["unexplained_where"]["window"] == "reflected"
    assert v["unexplained_where"]["residual_over_noise"] == pytest.approx(6.0**0.5)
    rows[1]["chi2_per_sample_after"] = 1.05
    assert verdict(300 * 2.05, 600, rows, dof=199)["explained"]


def test_static_precompression_is_the_declared_precompression_anywhere(bench):
    _, ctx, base, _ = bench
    state = get("static_precompression").apply(
        ctx, base, {"first_contact": 5, "contact_count": 3, "precompression_force_n": 2.0})
    ref = precompression_forces(base.chain.n_particles, (PrecompressionSpec(5, 7, 2.0),))
    np.testing.assert_allclose(state.chain.static_force - base.chain.static_force, ref)
    # a run reaching the wall stops above the wall contact
    end = get("static_precompression").apply(
        ctx, base, {"first_contact": 29, "contact_count": 6, "precompression_force_n": 1.0})
    assert np.isclose(np.sum(end.chain.static_force - base.chain.static_force), 0.0)


def test_sensor_mass_changes_only_the_sensor_beads(bench):
    _, ctx, base, _ = bench
    state = get("sensor_mass").apply(ctx, base, {"sensor_mass_kg": 0.6e-3})
    changed = np.flatnonzero(state.chain.mass != base.chain.mass) + 1
    np.testing.assert_array_equal(changed, [13, 18])
    assert np.all(state.chain.mass[changed - 1] == 0.6e-3)


def test_a_striker_faster_than_free_fall_is_implausible_not_named(bench):
    study, ctx, base, predictor = bench
    wf, _ = hidden_case(ctx, base, predictor,
                        {"striker_velocity": {"striker_velocity_m_per_s": 0.45}}, seed=31)
    d = diagnose(wf, study, fit=_fit(), effects=["striker_velocity", "wall_dissipation"])
    best = next(c for c in d.candidates if c.effect == "striker_velocity")
    assert best.parameters["striker_velocity_m_per_s"] == pytest.approx(0.45, rel=0.01)
    assert not best.plausible and "free fall" in best.notes[0]
    assert d.effect != "striker_velocity"
    assert not d.explained  # nothing plausible explains it


def test_jittered_shots_are_not_mistaken_for_an_effect(bench):
    """Four shots whose striker speeds scatter by 1 %: no effect is named, the data are
    explained, and each shot's speed is found."""
    study, ctx, base, predictor = bench
    wf, truth = hidden_shots(ctx, base, predictor, seed=32, shots=4, velocity_jitter=0.01)
    d = diagnose(wf, study, fit=_fit(),
                 effects=["striker_velocity", "daq_lowpass", "wall_stiffness"])
    assert d.effect == "none" and d.explained
    speeds = [s["striker_speed_m_per_s"] for s in d.noise["shots"]]
    np.testing.assert_allclose(speeds, list(truth["velocities"].values()), rtol=2e-3)
    assert d.noise["source"].startswith("shot-to-shot scatter of 4")


def test_an_effect_outside_the_library_is_not_explained(bench):
    study, ctx, base, predictor = bench
    wf = outside_case("heavy_striker", ctx, base, predictor, seed=33)
    d = diagnose(wf, study, fit=_fit(),
                 effects=["striker_velocity", "wall_stiffness", "daq_lowpass"])
    assert not d.explained
    where = d.verdict["unexplained_where"]
    assert where["residual_over_noise"] > 2.0 and where["channel"].startswith("bead@")
    assert "does not explain" in d.summary() or "no plausible" in d.summary()


def test_one_shot_without_pretrigger_falls_back_to_sample_differences(bench):
    _, ctx, base, predictor = bench
    wf, _ = hidden_case(ctx, base, predictor, seed=34,
                        rig=RigEffects(seed=34, pretrigger_s=0.0, noise=0.01))
    e = ensemble(wf, [("bead", 13), ("bead", 18)])
    assert e.source.startswith("sample-to-sample")
    peak = np.max(np.abs(wf.data), axis=0)
    np.testing.assert_allclose(np.sqrt(e.var[:, 0]), 0.01 * peak, rtol=0.2)
    assert dataclasses.is_dataclass(e)
