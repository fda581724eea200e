"""Event helpers of the compiled integrator: the dashpot-switch predictor and the search for
the first violated contact state."""

import numpy as np
import pytest

from msens.chain import kernel
from msens.chain.kernel import events


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
    tau = events.rate_zero(after(0.0), q, s, ql, sl, *past, hp, 2.0 * hp)
    assert tau == pytest.approx(tau_star, rel=1e-9)
    # A zero beyond the horizon is not reported.
    assert events.rate_zero(after(0.0), q, s, ql, sl, *past, hp, 0.5 * tau_star) == -1.0


def test_first_violation_of_a_gap():
    """A closed contact's gap (allowed sign >= 0) that turns negative at theta = 0.6."""
    # gap(theta) = (0.6 - theta) (1 + theta): value and derivative at both ends
    g = np.polynomial.Polynomial([0.6, -0.4, -1.0])
    th = events.first_violation(g(0.0), g.deriv()(0.0), g(1.0), g.deriv()(1.0), True)
    assert th == pytest.approx(0.6, abs=1e-12)


def test_a_state_just_switched_within_its_tolerance_is_no_violation():
    """A state switched at the step's start may sit on the wrong side by its time tolerance;
    if it leaves that side at once, the next sign change is the violation, not theta = 0
    (toggling it back would chatter). Moving further to the wrong side is one at once."""
    # Open contact (allowed gap <= 0): gap starts at +1e-6 (1e-6 of a step, times the
    # rate -1), falls, and rises through zero again at theta = 0.7.
    g = np.polynomial.Polynomial([1e-6, -1.0, 1.0 / 0.7 - 1e-6 / 0.49])
    assert g(0.7) == pytest.approx(0.0, abs=1e-12)
    th = events.first_violation(g(0.0), g.deriv()(0.0), g(1.0), g.deriv()(1.0), False)
    assert th == pytest.approx(0.7, abs=1e-5)
    # The same start value moving away from the allowed side, or too far on the wrong one.
    assert events.first_violation(1e-6, 1.0, 2.0, 1.0, False) == 0.0
    assert events.first_violation(1e-2, -1.0, 0.5, 3.0, False) == 0.0


def _random_contact_states(rng, n=30):
    """Padded states of n contacts near their switches: gaps, rates and relative accelerations
    of either sign, about 1/3 of the contacts open, half the closed ones' dashpots on, some
    without a dashpot."""
    p = kernel.padded_length(n)
    u, v, a = (np.zeros(p + 1) for _ in range(3))
    u[:n] = np.cumsum(rng.normal(0.0, 1e-7, n)[::-1])[::-1]
    v[:n] = rng.normal(0.0, 1e-2, n)
    a[:n] = rng.normal(0.0, 1e4, n)
    closed, damp, gam = (np.zeros(p) for _ in range(3))
    closed[:n] = rng.random(n) < 2.0 / 3.0
    damp[:n] = closed[:n] * (rng.random(n) < 0.5)
    gam[:n] = np.where(rng.random(n) < 0.9, 4.8, 0.0)
    return u, v, a, closed, damp, gam


@pytest.mark.parametrize("seed", range(20))
def test_vectorised_event_passes_match_their_scalar_definitions(seed):
    """The branch-free passes over the padded contact arrays flag exactly what the scalar
    tests they replaced select: violated states, dashpot-switch candidates, and (a superset
    of) the contacts whose Taylor-quadratic opening time is below the horizon."""
    rng = np.random.default_rng(seed)
    n = 30
    u, v, a, closed, damp, gam = _random_contact_states(rng, n)
    g = u[:n] - u[1:n + 1]
    r = v[:n] - v[1:n + 1]
    q = a[:n] - a[1:n + 1]
    c = closed[:n] > 0.0
    d = damp[:n] > 0.0
    tol = 1e-3
    h = 1e-6
    # Violated states (as a float formula before).
    gap_bad = (c & (g < 0.0)) | (~c & (g > 0.0))
    rate_bad = (gam[:n] > 0.0) & ((d & (r < -tol)) | (c & ~d & (r > tol)))
    for loading in (False, True):
        bad = gap_bad | (loading & rate_bad)
        for skip in (-1, *np.flatnonzero(bad)[:3]):
            expect = bool(np.any(np.delete(bad, skip) if skip >= 0 else bad))
            assert events.violated(u, v, closed, damp, gam, tol, loading, skip) is expect
    # Consistent states violate nothing; one contact put in the wrong state is found.
    ok_closed = np.r_[g > 0.0, np.zeros(closed.size - n)].astype(float)
    ok_damp = ok_closed * np.r_[r > 0.0, np.zeros(closed.size - n)]
    assert not events.violated(u, v, ok_closed, ok_damp, gam, 0.0, True, -1)
    k = int(rng.integers(n))
    ok_closed[k] = 1.0 - ok_closed[k]
    ok_damp[k] = ok_closed[k] * (r[k] > 0.0)
    assert events.violated(u, v, ok_closed, ok_damp, gam, 0.0, True, -1)
    assert not events.violated(u, v, ok_closed, ok_damp, gam, 0.0, True, k)
    # Dashpot-switch candidates (as the predictor's branches before).
    cand = (c & (gam[:n] > 0.0) & (r * q < 0.0) & (np.abs(r) > tol)
            & (np.abs(r) < 2.0 * h * np.abs(q)) & ((r > 0.0) == d))
    flag = np.full(closed.size, np.nan)
    assert events.switch_candidates(v, a, closed, damp, gam, tol, 2.0 * h, flag) == cand.sum()
    np.testing.assert_array_equal(flag, np.r_[cand, np.zeros(flag.size - n, bool)])
    # Openings: every contact with opening_time < T is flagged, and few others.
    for T in (1e-6, 1e-5, 1e-4):
        tau = np.array([events.opening_time(g[k], r[k], q[k], closed[k]) for k in range(n)])
        flag[:] = np.nan
        count = events.openings_within(u, v, a, closed, T, flag)
        assert count == flag.sum() and not flag[n:].any()
        assert np.all(flag[:n][tau < T] == 1.0)
        near = np.abs(tau / T - 1.0) < 1e-5
        assert np.all((flag[:n] == 1.0) == (tau < T) | near)
