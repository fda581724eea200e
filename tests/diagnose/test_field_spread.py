"""A fit's parameters over changes of the model (field_spread) and the widened intervals."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from msens.diagnose.effects.base import Parameter
from msens.diagnose.fit import (
    EffectFit,
    curvature_covariance,
    field_spread,
    fit_effect,
    linearisation_spread,
    widened,
)

T = np.linspace(0.0, 1.0, 400)
#: Two record shapes (one sensor) that a linear model adds with its parameters' weights.
SHAPES = np.array([np.sin(9 * T) * np.exp(-2 * T), np.exp(-((T - 0.4) / 0.08) ** 2)])
SIGMA = 0.01


@dataclass(frozen=True)
class Linear:
    """A toy effect: the record is sum_i a_i SHAPES[i]; one integer parameter rides along
    (held at its fitted value)."""

    space_: tuple
    name: str = "linear"
    grid_points: int = 12

    def strides(self, ctx):
        return {}

    def space(self, ctx, base):
        return list(self.space_)

    def apply(self, ctx, base, params):
        return dict(params)


class Records:
    """A toy predictor: records (runs, sensors = 1, nt) of the linear model."""

    def records(self, states):
        return np.array([[sum(s[f"a{i}"] * SHAPES[i] for i in range(len(SHAPES)))]
                         for s in states])


@dataclass
class Chi2:
    """A toy objective: chi^2 of the records against data y with noise SIGMA."""

    y: np.ndarray

    def rss(self, records):
        return np.array([float(np.sum((self.y - records[0]) ** 2) / SIGMA**2)])


def _fit(effect, objective, truth):
    space = effect.space(None, None)
    cont = [p for p in space if not p.integer]
    x0 = np.array([truth[p.name] for p in cont])

    def crit(xs):
        return np.array([objective.rss(Records().records([{**truth, **dict(
            zip((p.name for p in cont), x, strict=True))}])[0])[0] for x in xs])

    cov = curvature_covariance(crit, x0, np.array([p.lower for p in cont]),
                               np.array([p.upper for p in cont]))
    return EffectFit(effect="linear", parameters=dict(truth), state=None,
                     rss=objective.rss(Records().records([truth])[0]), n_parameters=len(space),
                     evaluations=0, curvature=cov)


def test_field_spread_is_the_exact_move_of_a_linear_fit():
    """For a model linear in its parameters, a record change d = sum_i c_i SHAPES[i] moves
    the optimum by exactly -c: the spread is the second moment of the c's."""
    effect = Linear((Parameter("a0", -5.0, 5.0), Parameter("a1", -5.0, 5.0),
                     Parameter("n", 1, 4, integer=True)))
    truth = {"a0": 1.2, "a1": -0.7, "n": 2}
    y = Records().records([truth])[0][0]
    objective = Chi2(y)
    fit = _fit(effect, objective, truth)
    c = np.random.default_rng(3).normal(scale=[0.02, 0.05], size=(6, 2))
    changes = np.einsum("dk,kn->dn", c, SHAPES)[:, None, :]
    got = field_spread(effect, None, None, Records(), objective, np.ones(1), fit, changes)
    np.testing.assert_allclose(got, c.T @ c / len(c), rtol=1e-6, atol=1e-12)


def test_widened_intervals_add_the_spread_to_the_curvature():
    """The widened interval's half-width is z sqrt(curvature + spread) (search variables);
    a log parameter's interval is symmetric in log10 of the parameter."""
    effect = Linear((Parameter("a0", 1e-3, 1e3, log=True),))
    fit = EffectFit(effect="linear", parameters={"a0": 10.0}, state=None, rss=np.zeros(1),
                    n_parameters=1, evaluations=0, curvature=np.array([[1e-4]]),
                    widening=4.0)
    lo, hi = widened(effect, None, None, fit, np.array([[3e-4]]))["a0"]
    half = 1.959963984540054 * np.sqrt(4.0 * 1e-4 + 3e-4)
    assert np.log10(hi) - 1.0 == pytest.approx(half, rel=1e-9)
    assert 1.0 - np.log10(lo) == pytest.approx(half, rel=1e-9)


def test_a_refit_near_an_earlier_fit():
    """A refit started from an earlier optimum searches a few grid points around it (the
    integer parameter held) and finds the optimum the whole search finds, with a fraction
    of the runs; started far from it, its best point lies at the end of that window and the
    whole grid is searched."""
    effect = Linear((Parameter("a0", -2.0, 2.0), Parameter("a1", -2.0, 2.0),
                     Parameter("n", 1, 4, integer=True)))
    truth = {"a0": 0.73, "a1": -1.31, "n": 2}
    rng = np.random.default_rng(8)
    objective = Chi2(Records().records([truth])[0][0] + SIGMA * rng.normal(size=T.size))
    whole = fit_effect(effect, None, None, Records(), objective, np.ones(1))
    near = fit_effect(effect, None, None, Records(), objective, np.ones(1),
                      near={**whole.parameters, "a0": whole.parameters["a0"] + 0.1})
    for k in ("a0", "a1"):
        assert near.parameters[k] == pytest.approx(whole.parameters[k], abs=0.01)
        assert near.intervals[k] == pytest.approx(whole.intervals[k], abs=0.01)
    assert near.parameters["n"] == whole.parameters["n"]
    assert near.evaluations < whole.evaluations / 3
    far = fit_effect(effect, None, None, Records(), objective, np.ones(1),
                     near={"a0": -1.9, "a1": 1.9, "n": 2})
    assert far.parameters["a0"] == pytest.approx(whole.parameters["a0"], abs=1e-6)
    assert far.evaluations == whole.evaluations


def test_linearisation_spread_is_the_move_between_the_two_fits():
    """The move from the first fit to the refit, in search variables (log10 for a log
    parameter; integer parameters left out), as the outer product d d^T."""
    effect = Linear((Parameter("a0", 1e-3, 1e3, log=True), Parameter("a1", -5.0, 5.0),
                     Parameter("n", 1, 4, integer=True)))
    got = linearisation_spread(effect, None, None, {"a0": 10.0, "a1": 0.5, "n": 2},
                               {"a0": 20.0, "a1": 0.2, "n": 3})
    d = np.array([np.log10(2.0), -0.3])
    np.testing.assert_allclose(got, np.outer(d, d), rtol=1e-12)
    assert not np.any(linearisation_spread(effect, None, None, {"a0": 3.0, "a1": 1.0, "n": 1},
                                           {"a0": 3.0, "a1": 1.0, "n": 1}))
