"""The shared likelihood: noise plus the model's own uncertainty."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from msens.diagnose.candidates import THRESHOLD
from msens.diagnose.effects import get
from msens.diagnose.likelihood import (
    NO_FIELD_MODEL,
    PHYSICS_MSS,
    ModelUncertainty,
    chi2,
    log_likelihood,
    model_uncertainty,
    variance_split,
)
from msens.diagnose.objective import WaveformObjective
from msens.diagnose.predict import setup_result
from msens.diagnose.verdict import verdict
from msens.diagnose.where import window_residuals
from msens.readout.sensors import SensorKind
from msens.synth import RigEffects, synthesize


def test_model_variance_is_amplitude_and_timing_error():
    t = np.linspace(0.0, 400e-6, 4001)
    m = 2.0 * np.exp(-(((t - 300e-6) / 10e-6) ** 2))
    slope = -2.0 * (t - 300e-6) / (10e-6) ** 2 * m
    u = ModelUncertainty(relative_amplitude=0.005, relative_timing=1e-3)
    np.testing.assert_allclose(u.variance(m, t), (0.005 * m) ** 2 + (1e-3 * t * slope) ** 2,
                               rtol=1e-3, atol=1e-12 * np.max(m) ** 2)
    assert np.all(ModelUncertainty().variance(m, t) == 0.0)
    with pytest.raises(ValueError):
        ModelUncertainty(relative_amplitude=-0.1)


def test_only_a_physics_mss_has_a_field_model_uncertainty():
    assert model_uncertainty(SensorKind.MSS, True) is PHYSICS_MSS
    assert model_uncertainty(SensorKind.MSS, False) is NO_FIELD_MODEL
    assert model_uncertainty(SensorKind.BEAD, False) is NO_FIELD_MODEL
    assert PHYSICS_MSS.relative_timing > 0 and PHYSICS_MSS.relative_amplitude > 0


def test_log_likelihood_is_gaussian_with_the_summed_variance():
    rng = np.random.default_rng(0)
    r = rng.normal(size=50)
    noise, model = np.full(50, 0.8), np.linspace(0.0, 0.5, 50)
    expected = stats.norm.logpdf(r, scale=np.sqrt(noise + model)).sum()
    assert log_likelihood(r, noise, model) == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(chi2(r, noise, model), r**2 / (noise + model))
    split = variance_split(noise, model)
    assert split["model_uncertainty_share"] == pytest.approx(12.5 / 52.5)
    assert split["noise_share"] + split["model_uncertainty_share"] == pytest.approx(1.0)


def _objective(ctx, base, predictor, result, records0, effect, params, uncertain):
    state = get(effect).apply(ctx, base, params)
    wf = synthesize(setup_result(ctx, state, predictor), RigEffects(noise=0.01, seed=3,
                                                                    shots=8))
    obj = WaveformObjective(wf, result, np.zeros(8, int))
    if uncertain:
        obj.add_model_uncertainty(records0)
    return obj, predictor.records([state])[0]


def test_slightly_different_field_is_explained_and_a_real_effect_still_found(mss):
    """Physics MsS, 8 shots, 1 % noise. Data whose magnets are 1 % stronger (the field
    model's accuracy): the baseline explains them with less chi^2 than against the noise
    alone. A 3 % faster striker: still far from explained, its chi^2 drop far above the
    naming threshold."""
    ctx, base, predictor, result, records0 = mss
    chis = []
    for uncertain in (False, True):
        obj, _ = _objective(ctx, base, predictor, result, records0, "magnet_remanence",
                            {"remanence_factor": 1.01}, uncertain)
        n = float(obj.n_obs.sum())
        chi = float(obj.rss(records0).sum())
        chis.append(chi / n)
        v = verdict(chi, n, window_residuals(obj, records0, records0, result),
                    obj.ensemble.dof)
        assert v["explained"]
    assert chis[1] < 0.8 * chis[0]
    share = obj.variance_split()["model_uncertainty_share"]
    assert 0.3 < share < 0.9  # 8 shots: the model's uncertainty is most of the variance
    obj, records1 = _objective(ctx, base, predictor, result, records0, "striker_velocity",
                               {"striker_velocity_m_per_s": 1.03 * base.velocity}, True)
    n = float(obj.n_obs.sum())
    chi0, chi1 = float(obj.rss(records0).sum()), float(obj.rss(records1).sum())
    windows = window_residuals(obj, records0, records0, result)
    assert not verdict(chi0, n, windows, obj.ensemble.dof)["explained"]
    assert chi0 - chi1 > 100 * THRESHOLD
    for w in windows:
        assert 0.0 <= w["model_uncertainty_share"] < 1.0
        assert w["chi2_per_sample_after_noise_only"] >= w["chi2_per_sample_after"]
