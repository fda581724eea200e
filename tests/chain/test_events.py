"""Event helpers of the compiled integrator: the dashpot-switch predictor and the search for
the first violated contact state."""

import numpy as np
import pytest

from msens.chain import kernel


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("switch_now", [False, True])
def test_rate_predictor_is_exact_for_quintic_rates(seed, switch_now):
    """The predicted zero of an approach rate comes from the quintic through the rate and
    its first two derivatives now and one step earlier: exact (to rounding) when the rate is
    a quintic in time, also when a switch nearby now adds jumps dq tau + ds tau^2 / 2 to it
    (given the derivatives' left limits)."""
    rng = np.random.default_rng(seed)
    hp = rng.uniform(0.5e-6, 3e-6)  # s
    tau_star = rng.uniform(0.1, 1.8) * hp  # the zero, s after now
    # rate(tau) = c (tau - tau*) (1 + small higher terms), m/s, tau = time from now
    c = rng.choice([-1.0, 1.0]) * rng.uniform(1e3, 1e5)  # m/s^2
    extra = np.polynomial.Polynomial(
        np.r_[1.0, rng.uniform(-0.2, 0.2, 4) / hp ** np.arange(1, 5)])
    after = np.polynomial.Polynomial([-c * tau_star, c]) * extra  # for tau >= 0
    jumps = np.polynomial.Polynomial([0.0, *(rng.uniform(-0.3, 0.3, 2) * c / [1, hp])])
    before = after - jumps if switch_now else after  # for tau <= 0
    q, s = after.deriv(1)(0.0), after.deriv(2)(0.0)
    ql, sl = before.deriv(1)(0.0), before.deriv(2)(0.0)
    past = (before(-hp), before.deriv(1)(-hp), before.deriv(2)(-hp))
    tau = kernel._rate_zero(after(0.0), q, s, ql, sl, *past, hp, 2.0 * hp)
    assert tau == pytest.approx(tau_star, rel=1e-9)
    # A zero beyond the horizon is not reported.
    assert kernel._rate_zero(after(0.0), q, s, ql, sl, *past, hp, 0.5 * tau_star) == -1.0


def test_first_violation_of_a_gap():
    """A closed contact's gap (allowed sign >= 0) that turns negative at theta = 0.6."""
    # gap(theta) = (0.6 - theta) (1 + theta): value and derivative at both ends
    g = np.polynomial.Polynomial([0.6, -0.4, -1.0])
    th = kernel._first_violation(g(0.0), g.deriv()(0.0), g(1.0), g.deriv()(1.0), True)
    assert th == pytest.approx(0.6, abs=1e-12)


def test_a_state_just_switched_within_its_tolerance_is_no_violation():
    """A state switched at the step's start may sit on the wrong side by its time tolerance;
    if it leaves that side at once, the next sign change is the violation, not theta = 0
    (toggling it back would chatter). Moving further to the wrong side is one at once."""
    # Open contact (allowed gap <= 0): gap starts at +1e-6 (1e-6 of a step, times the
    # rate -1), falls, and rises through zero again at theta = 0.7.
    g = np.polynomial.Polynomial([1e-6, -1.0, 1.0 / 0.7 - 1e-6 / 0.49])
    assert g(0.7) == pytest.approx(0.0, abs=1e-12)
    th = kernel._first_violation(g(0.0), g.deriv()(0.0), g(1.0), g.deriv()(1.0), False)
    assert th == pytest.approx(0.7, abs=1e-5)
    # The same start value moving away from the allowed side, or too far on the wrong one.
    assert kernel._first_violation(1e-6, 1.0, 2.0, 1.0, False) == 0.0
    assert kernel._first_violation(1e-2, -1.0, 0.5, 3.0, False) == 0.0
