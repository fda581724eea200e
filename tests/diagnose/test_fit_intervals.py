"""Honest parameters: intervals from the curvature of the fit, fits at a bound not named."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from msens.diagnose.candidates import decide, demoted, floor_evidence, settle
from msens.diagnose.diagnosis import Candidate, Diagnosis
from msens.diagnose.effects.base import Effect, Parameter
from msens.diagnose.effects.static_precompression import STRIDES
from msens.diagnose.fit import (
    Z_LEVEL,
    at_bounds,
    curvature_covariance,
    fit_effect,
    parameter_intervals,
)
from msens.workflows.diagnose import format_diagnosis


def _quadratic(x0: np.ndarray, cov: np.ndarray, chi0: float = 0.0):
    inv = np.linalg.inv(cov)

    def crit(xs):
        return np.array([chi0 + (x - x0) @ inv @ (x - x0) for x in xs])
    return crit


def test_curvature_of_a_known_chi2_gives_its_covariance():
    # chi^2 = (x - a)^T C^-1 (x - a): the covariance is C (correlated, different scales)
    a = np.array([0.3, -2.0])
    cov = np.array([[0.01**2, 0.6 * 0.01 * 0.2], [0.6 * 0.01 * 0.2, 0.2**2]])
    lower, upper = np.array([0.0, -5.0]), np.array([1.0, 5.0])
    got = curvature_covariance(_quadratic(a, cov), a, lower, upper)
    np.testing.assert_allclose(got, cov, rtol=1e-6, atol=1e-12)
    (lo0, hi0), (lo1, hi1) = parameter_intervals(a, got, lower, upper)
    assert (lo0, hi0) == pytest.approx((0.3 - Z_LEVEL * 0.01, 0.3 + Z_LEVEL * 0.01))
    assert (lo1, hi1) == pytest.approx((-2.0 - Z_LEVEL * 0.2, -2.0 + Z_LEVEL * 0.2))


def test_a_poor_fit_widens_the_interval_by_its_reduced_chi2():
    a, cov = np.array([0.5]), np.array([[1e-4]])
    lower, upper = np.array([0.0]), np.array([1.0])
    # chi^2 at the optimum is 4 x its degrees of freedom: the variance is 4 x larger
    got = curvature_covariance(_quadratic(a, cov, chi0=4.0 * 99), a, lower, upper, n_obs=100)
    assert got[0, 0] == pytest.approx(4e-4, rel=1e-6)
    good = curvature_covariance(_quadratic(a, cov, chi0=90.0), a, lower, upper, n_obs=100)
    assert good[0, 0] == pytest.approx(1e-4, rel=1e-6)


def test_curvature_at_an_end_of_the_range_uses_the_inner_side():
    a, cov = np.array([1.0]), np.array([[0.05**2]])
    got = curvature_covariance(_quadratic(a, cov), a, np.array([0.0]), np.array([1.0]))
    assert got[0, 0] == pytest.approx(0.05**2, rel=1e-6)
    assert at_bounds(a, np.array([0.0]), np.array([1.0])).tolist() == [True]
    assert at_bounds(np.array([0.9]), np.array([0.0]), np.array([1.0])).tolist() == [False]


def test_a_flat_direction_gets_the_searched_span():
    def crit(xs):
        return np.array([(x[0] - 0.5) ** 2 / 1e-4 for x in xs])  # x[1] does not matter
    got = curvature_covariance(crit, np.array([0.5, 3.0]), np.array([0.0, 0.0]),
                               np.array([1.0, 10.0]))
    assert got[0, 0] == pytest.approx(1e-4, rel=1e-6)
    assert np.sqrt(got[1, 1]) == pytest.approx(10.0, rel=1e-6)


class _Predictor:
    """Records of toy states: the state is the parameter value itself."""

    def records(self, states):
        return [np.array([s]) for s in states]


class _Objective:
    """chi^2 = ((x - truth) / sd)^2 on one 'sensor'."""

    def __init__(self, truth: float, sd: float):
        self.truth, self.sd = truth, sd
        self.n_obs = np.array([np.inf])

    def rss(self, records):
        return np.array([((records[0] - self.truth) / self.sd) ** 2])


def _toy(log: bool = False) -> Effect:
    lo, hi = (0.1, 10.0) if log else (0.0, 1.0)
    return Effect(name="toy", description="a toy effect",
                  space=lambda ctx, base: (Parameter("x_m", lo, hi, log=log),),
                  baseline=lambda ctx, base: {"x_m": lo},
                  apply=lambda ctx, base, p: float(p["x_m"]))


def test_fit_effect_reports_the_curvature_interval():
    fit = fit_effect(_toy(), None, None, _Predictor(), _Objective(0.437, 0.01), np.ones(1))
    assert fit.parameters["x_m"] == pytest.approx(0.437, abs=1e-4)
    lo, hi = fit.intervals["x_m"]
    assert lo == pytest.approx(0.437 - Z_LEVEL * 0.01, abs=2e-4)
    assert hi == pytest.approx(0.437 + Z_LEVEL * 0.01, abs=2e-4)
    assert fit.at_bound == ()


def test_fit_effect_interval_of_a_log_parameter_is_asymmetric_in_si():
    # chi^2 quadratic in the value: in log10 the interval maps back around the optimum
    fit = fit_effect(_toy(log=True), None, None, _Predictor(), _Objective(2.0, 0.05),
                     np.ones(1))
    lo, hi = fit.intervals["x_m"]
    assert lo < 2.0 < hi
    assert hi - lo == pytest.approx(2 * Z_LEVEL * 0.05, rel=0.03)


def test_a_fit_pinned_at_a_bound_is_flagged():
    fit = fit_effect(_toy(), None, None, _Predictor(), _Objective(1.3, 0.05), np.ones(1))
    assert fit.parameters["x_m"] == pytest.approx(1.0, abs=1e-3)
    assert fit.at_bound == ("x_m",)
    assert fit.intervals["x_m"][1] == pytest.approx(1.0)


def _wall() -> Effect:
    """A wall modulus searched in log10 from a 200 GPa baseline, floor 5 %, with an
    integer parameter without a baseline."""
    return Effect(name="wall", description="a toy wall",
                  space=lambda ctx, base: (Parameter("e_pa", 2e9, 1e12, log=True, floor=10e9),
                                           Parameter("k", 1, 3, integer=True)),
                  baseline=lambda ctx, base: {"e_pa": 200e9, "k": None},
                  apply=lambda ctx, base, p: p)


def test_floor_evidence_is_the_chi2_rise_to_the_floors_edge_under_the_interval():
    e = _wall()
    # 150 GPa, interval half-width 0.02 decades toward the baseline: the edge 190 GPa is
    # log10(190/150) = 0.1027 decades away, (1.96 * 0.1027 / 0.02)^2 = 101
    iv = (150e9 * 10**-0.02, 150e9 * 10**0.02)
    rise, why = floor_evidence(e, None, None, {"e_pa": 150e9, "k": 2}, {"e_pa": iv})
    assert rise == pytest.approx((Z_LEVEL * np.log10(190 / 150) / 0.02) ** 2, rel=1e-9)
    assert "e_pa" in why and "1.9e+11" in why
    # 184 GPa with an interval reaching 189 GPa: the edge 1.1 half-widths away, ~4.6
    rise, _ = floor_evidence(e, None, None, {"e_pa": 184e9, "k": 2},
                             {"e_pa": (178e9, 189e9)})
    half = np.log10(189 / 184)
    assert rise == pytest.approx((Z_LEVEL * np.log10(190 / 184) / half) ** 2, rel=1e-9)
    assert rise < 10.0
    # the interval covers the edge: a rise below the interval's own level (Z^2)
    rise, _ = floor_evidence(e, None, None, {"e_pa": 184e9, "k": 2},
                             {"e_pa": (170e9, 195e9)})
    assert rise < Z_LEVEL**2
    # within the floor, or no interval: nothing to weigh
    assert floor_evidence(e, None, None, {"e_pa": 195e9, "k": 1},
                          {"e_pa": (190e9, 200e9)})[0] == np.inf
    assert floor_evidence(e, None, None, {"e_pa": 150e9, "k": 1}, {})[0] == np.inf


def test_a_demoted_winner_becomes_a_negligible_change_that_blocks_lesser_ones():
    fits = [SimpleNamespace(effect="wall_stiffness"), SimpleNamespace(effect="tube_friction")]
    wall, drag = _cand("wall_stiffness", 136.0), _cand("tube_friction", 60.0)
    assert decide([wall, drag], fits, 10.0)[0] is wall
    weak = demoted(wall, 4.6, "e_pa = 1.84e11", 10.0)
    assert not weak.significant and "within the model's uncertainty" in weak.notes[-1]
    assert weak.near_floor and weak.to_json()["near_floor"] is True
    report = {"setup": "mss", "mode": "waveform", "disagreement": {"where": "x"},
              "candidates": [weak.to_json(), drag.to_json()],
              "passes": [{"effect": "none", "parameters": {}, "misfit_before": 1.0,
                          "misfit_after": 1.0, "explained": True}]}
    text = format_diagnosis(report)
    assert "wall_stiffness" in text and "[near floor]" in text
    assert "[below floor]" not in text and "[near floor]: beyond its floor" in text
    # nothing practical is missing: the demoted wall (136) scores above the drag (60)
    assert decide([weak, drag], fits, 10.0) == (None, None)
    # a lesser candidate that still beats it by the threshold is named
    strong = dataclasses.replace(drag, score=150.0)
    assert decide([weak, strong], fits, 10.0)[0] is strong


def test_settle_demotes_a_wall_within_the_models_uncertainty_of_its_floor():
    # the library's wall on a 200 GPa wall: floor 10 GPa, edge 190 GPa
    ctx = SimpleNamespace(study=SimpleNamespace(chain=SimpleNamespace(
        wall=SimpleNamespace(youngs_modulus_pa=200e9))))
    drag = _cand("tube_friction", 60.0)
    wall = dataclasses.replace(_cand("wall_stiffness", 136.0),
                               parameters={"wall_youngs_modulus_pa": 183.6e9},
                               intervals={"wall_youngs_modulus_pa": (178.2e9, 189.2e9)})
    # the sensor resonance's wall: 1.1 half-widths from the edge, rise 5
    cands, settled = settle([wall, drag], wall, ctx, None, 10.0)
    assert not settled and cands[0].near_floor and not cands[0].significant
    assert cands[1] is drag
    # a narrower interval, [180, 187] GPa: 1.9 half-widths, rise 13: the name stands
    sure = dataclasses.replace(wall, intervals={"wall_youngs_modulus_pa": (180e9, 187e9)})
    assert settle([sure, drag], sure, ctx, None, 10.0) == ([sure, drag], True)
    assert settle([drag], None, ctx, None, 10.0) == ([drag], True)


def _cand(effect: str, score: float, **kw) -> Candidate:
    return Candidate(effect=effect, parameters={"remanence_factor": 1.5}, baseline={},
                     chi2=1.0, misfit=1.0, score=score, n_parameters=1, **kw)


def test_a_fit_at_a_bound_is_not_named_and_the_verdict_says_so():
    pinned = _cand("magnet_remanence", 300.0, at_bound=("remanence_factor",),
                   intervals={"remanence_factor": (1.45, 1.5)})
    other = _cand("wall_dissipation", 40.0)
    # the pinned fit is not named, and it fits so much better than the next that the
    # next is not the answer either
    assert decide([pinned, other], [], 10.0) == (None, None)
    assert decide([pinned], [], 10.0) == (None, None)
    # pinned beyond its physical range too (a 30 N force at the top of its search): still
    # blocks a lesser effect
    beyond = dataclasses.replace(pinned, plausible=False)
    assert decide([beyond, other], [], 10.0) == (None, None)
    fits = [SimpleNamespace(effect="wall_dissipation")]
    assert decide([other, dataclasses.replace(beyond, score=5.0)], fits, 10.0)[0] is other
    d = Diagnosis(mode="waveform", setup="mss", effect="none", parameters={},
                  misfit_before=2.0, misfit_after=2.0, candidates=(pinned,), threshold=10.0,
                  n_obs=100, sigma=(1.0,), added=(), refit=(), gamma_contact=1.0,
                  gamma_wall=0.0, disagreement={"where": "x", "windows": []}, simulations=1,
                  elapsed_s=0.0, verdict={"explained": False, "windows": []}, noise={},
                  before=None, after=None)
    assert "closest, magnet_remanence, has its fit at the bound" in d.summary()
    js = d.to_json()
    assert js["closest_at_bound"]["effect"] == "magnet_remanence"
    assert js["candidates"][0]["at_bound"] is True
    assert js["candidates"][0]["intervals"]["remanence_factor"] == {
        "value": 1.5, "lower": 1.45, "upper": 1.5, "at_bound": True}
    report = {**js, "passes": [{"effect": "none", "parameters": {}, "misfit_before": 2.0,
                                "misfit_after": 2.0, "explained": False,
                                "summary": d.summary()}]}
    text = format_diagnosis(report)
    assert "[at bound]" in text and "remanence_factor=1.5 [1.45, 1.5]" in text
    assert "model's own uncertainty" not in text
    report["noise"] = {"model_uncertainty": {"noise_share": 0.46,
                                             "model_uncertainty_share": 0.54}}
    assert "noise (46 % of the variance) and the model's own uncertainty (54 %)" in \
        format_diagnosis(report)


def test_a_named_effect_reports_its_interval():
    c = dataclasses.replace(_cand("magnet_remanence", 50.0),
                            parameters={"remanence_factor": 1.1},
                            intervals={"remanence_factor": (1.05, 1.16)})
    d = Diagnosis(mode="waveform", setup="mss", effect="magnet_remanence",
                  parameters={"remanence_factor": 1.1}, misfit_before=2.0, misfit_after=1.0,
                  candidates=(c,), threshold=10.0, n_obs=100, sigma=(1.0,), added=(),
                  refit=(), gamma_contact=1.0, gamma_wall=0.0,
                  disagreement={"where": "x", "windows": []}, simulations=1, elapsed_s=0.0,
                  verdict={"explained": True, "windows": []}, noise={}, before=None,
                  after=None)
    iv = d.to_json()["parameter_intervals"]["remanence_factor"]
    assert (iv["lower"], iv["value"], iv["upper"]) == (1.05, 1.1, 1.16)
    assert d.to_json()["closest_at_bound"] is None


class _IntObjective:
    """chi^2 smooth in an integer position k, a count c and a force f (one 'sensor')."""

    n_obs = np.array([np.inf])

    def rss(self, records):
        k, c, f = records
        return np.array([((k - 17) / 2.0) ** 2 + (c - 4) ** 2 + ((f - 2.5) / 0.05) ** 2])


class _IntPredictor:
    def records(self, states):
        return [np.array(s) for s in states]


def test_coarse_to_fine_search_finds_the_exhaustive_optimum_for_less():
    space = (Parameter("first_contact", 2, 29, integer=True),
             Parameter("contact_count", 1, 6, integer=True),
             Parameter("force_n", 0.05, 30.0, log=True))

    def effect(strides):
        return Effect(name="toy", description="toy", space=lambda ctx, base: space,
                      baseline=lambda ctx, base: {"force_n": 0.0},
                      apply=lambda ctx, base, p: (p["first_contact"], p["contact_count"],
                                                  p["force_n"]),
                      grid_points=6, strides=lambda ctx: strides)

    full = fit_effect(effect({}), None, None, _IntPredictor(), _IntObjective(), np.ones(1))
    # the strides of static_precompression on physics MsS data
    fast = fit_effect(effect({"first_contact": STRIDES["first_contact"],
                              "contact_count": STRIDES["contact_count"]}), None, None,
                      _IntPredictor(), _IntObjective(), np.ones(1))
    for fit in (full, fast):
        assert (fit.parameters["first_contact"], fit.parameters["contact_count"]) == (17, 4)
        assert fit.parameters["force_n"] == pytest.approx(2.5, rel=1e-3)
        lo, hi = fit.intervals["force_n"]
        assert lo == pytest.approx(2.5 - Z_LEVEL * 0.05, rel=2e-3)
        assert hi == pytest.approx(2.5 + Z_LEVEL * 0.05, rel=2e-3)
    assert fast.evaluations < 0.4 * full.evaluations  # 372 of 1023


def test_a_fit_at_the_edge_of_its_physical_range_is_flagged():
    def toy() -> Effect:
        return Effect(name="toy", description="a toy effect",
                      space=lambda ctx, base: (Parameter("x_m", 0.0, 1.0,
                                                         plausible=(0.0, 0.6)),),
                      baseline=lambda ctx, base: {"x_m": 0.0},
                      apply=lambda ctx, base, p: float(p["x_m"]))

    at_edge = fit_effect(toy(), None, None, _Predictor(), _Objective(0.599, 0.01),
                         np.ones(1))
    assert at_edge.at_bound == ("x_m",)
    inside = fit_effect(toy(), None, None, _Predictor(), _Objective(0.55, 0.01), np.ones(1))
    assert inside.at_bound == ()
    # beyond the physical range: implausible (judged elsewhere), not "at bound"
    beyond = fit_effect(toy(), None, None, _Predictor(), _Objective(0.7, 0.01), np.ones(1))
    assert beyond.at_bound == ()
