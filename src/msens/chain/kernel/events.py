"""Contact events of the chain kernel: finding, predicting and taking state switches.

Each contact carries an open/closed state and (loading-only dashpot) a dashpot state, frozen
during a step. This module finds violated states at a step's end (:func:`violated`,
:func:`first_violation`), foresees openings (:func:`openings_within`, :func:`opening_time`)
and dashpot switches (:func:`switch_candidates`, :func:`rate_zero`), and switches a state
with the local updates it needs (:func:`switch`). The per-step passes are branch-free counts
over the padded arrays (they vectorise); the scalar work then visits only flagged contacts.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain.kernel.forces import (
    FM,
    LAW_HKK,
    LAW_LINEAR_LOADING,
    dforce,
    force,
    jerks,
)
from msens.chain.kernel.hermite import hermite3, hermite3_slope
from msens.chain.kernel.noalias import njit_noalias

#: A contact whose crossing falls within this fraction of a step from its start toggles at
#: once.
THETA_NOW = 1e-9
#: Newton refinement of a crossing stops when |gap| < GAP_TOL * h * |d(gap)/dt|, i.e. the
#: switch time errs by less than GAP_TOL steps, where the force jumps there (by gamma * rate:
#: a dashpot acting at the switch). Where it is continuous (Kuwabara-Kono, no dashpot, or
#: the loading-only dashpot at an opening) GAP_TOL_SMOOTH: an error e in the time changes the
#: impulse by ~ A rate^1.5 e^2.5 and the force near the switch by ~ A (rate e)^1.5, < 1e-7 of
#: the peak on the paper chain.
GAP_TOL = 1e-7
GAP_TOL_SMOOTH = 1e-4
#: Newton iterations at most per crossing.
NEWTON_MAX = 4
#: A predicted dashpot switch is accepted at the end of a step when the rate's zero lies
#: within this fraction of the step from it.
PRED_TOL = 1e-3
#: A state that switched at a step's start may have the wrong sign there by the tolerance of
#: its time (GAP_TOL_SMOOTH, PRED_TOL steps): not a violation if it leaves the wrong sign
#: within this many steps.
SWITCH_SLACK = 2e-3
#: A closing is grazing when its rate changes by itself (2 |rate| / |relative acceleration|)
#: within 1 / CLOSE_FRAC first steps; its grading then deepens, to at most CLOSE_MAX levels.
CLOSE_FRAC = 0.5
CLOSE_MAX = 8


@nb.njit(cache=True)
def first_violation(g0, r0, g1, r1, closed):
    """Smallest theta in [0, 1] where the cubic Hermite gap leaves its allowed sign.

    An open contact (closed=False) must keep gap <= 0, a closed one gap >= 0. ``r0``/``r1``
    are the gap rates times the step.
    """
    sgn = -1.0 if closed else 1.0
    p0 = sgn * g0
    p1 = sgn * g1
    d0 = sgn * r0
    d1 = sgn * r1
    if p0 > 0.0:
        if p0 > -SWITCH_SLACK * d0:
            return 0.0
        # Moving into the allowed sign within SWITCH_SLACK steps: the state switched here,
        # within the tolerance of its time. (Toggling it back would chatter.)
        p0 = 0.0
    # Bracket the first sign change on a coarse grid, then bisect.
    lo = 0.0
    hi = 1.0
    m = 16
    for j in range(1, m + 1):
        th = j / m
        if hermite3(p0, d0, p1, d1, th) > 0.0:
            hi = th
            lo = (j - 1) / m
            break
    # Newton on the cubic inside the bracket, falling back to bisection when a Newton step
    # leaves it; the bracket keeps p(lo) <= 0 < p(hi), and hi is returned.
    th = 0.5 * (lo + hi)
    for _ in range(60):
        if hi - lo < 1e-13:
            break
        p = hermite3(p0, d0, p1, d1, th)
        if p > 0.0:
            hi = th
        else:
            lo = th
        dp = hermite3_slope(p0, d0, p1, d1, th)
        step = p / dp if dp != 0.0 else 0.0
        nxt = th - step
        if abs(step) < 1e-14 and p > 0.0:
            break
        th = nxt if lo < nxt < hi else 0.5 * (lo + hi)
    return hi


@nb.njit(cache=True)
def rate_zero(r, q, s, ql, sl, rp, qp, sp, hp, tau_max):
    """Time (s) to the first zero in (0, tau_max) of an approach rate, -1.0 if none found.

    Extrapolates the quintic Hermite polynomial through the rate and its first two time
    derivatives now (r and the left limits ql, sl) and one step ``hp`` earlier (rp, qp, sp),
    plus the jumps (q - ql) tau + (s - sl) tau^2 / 2 of a switch nearby now; by Newton from
    the linear estimate -r / q.
    """
    # Coefficients x_i = c_i H^i of the terms of degree 3, 4, 5 in tau (H = -hp) that the
    # Taylor quadratic at tau = 0 needs to match the earlier data.
    H = -hp
    R0 = rp - (r + H * (ql + 0.5 * sl * H))
    R1 = (qp - (ql + sl * H)) * H
    R2 = (sp - sl) * H * H
    x5 = 0.5 * R2 - 3.0 * R1 + 6.0 * R0
    x4 = R1 - 3.0 * R0 - 2.0 * x5
    x3 = R0 - x4 - x5
    c3 = x3 / H**3
    c4 = x4 / H**4
    c5 = x5 / H**5
    tau = -r / q
    for _ in range(8):
        f = r + tau * (q + tau * (0.5 * s + tau * (c3 + tau * (c4 + tau * c5))))
        df = q + tau * (s + tau * (3.0 * c3 + tau * (4.0 * c4 + tau * 5.0 * c5)))
        if df == 0.0:
            return -1.0
        dtau = f / df
        tau -= dtau
        if not 0.0 < tau < tau_max:
            return -1.0
        if abs(dtau) < 1e-10 * tau_max:
            return tau
    return -1.0


@nb.njit(cache=True, inline="always")
def closing_grade(r, q, levels):
    """Grading depth after a contact closed at approach rate r and relative acceleration q
    (both times powers of the nominal step: r dt, q dt^2): at least ``levels``, deeper while
    the first step dt 2^-g exceeds CLOSE_FRAC of the time 2 |r| / |q| over which the rate
    changes by itself (a slow, grazing closing: there the expansion in sqrt(t - t0)
    converges only over that time)."""
    g = levels
    while g < CLOSE_MAX and CLOSE_FRAC * 2.0 * abs(r) < abs(q) * 0.5**g:
        g += 1
    return g


@nb.njit(cache=True, fastmath=FM)
def update_near(k, u, v, a, jk, with_jerk, cA, cg, law, load, inv_m, drag):
    """After contact k switched: the accelerations of its two particles (and with
    ``with_jerk`` the jerks of the four around it) anew, the only ones that change; the same
    arithmetic as :func:`accelerations` and :func:`jerks` (padded layout)."""
    p = cA.shape[0]
    hkk = law == LAW_HKK
    # Each contact's force (and its rate) once, carried over as in the full passes.
    f_prev = 0.0
    if k > 0:
        f_prev = force(u[k - 1] - u[k], v[k - 1] - v[k], cA[k - 1], cg[k - 1], hkk)
    for i in range(k, min(k + 2, p)):
        f = force(u[i] - u[i + 1], v[i] - v[i + 1], cA[i], cg[i], hkk)
        a[i] = (load[i] + f_prev - f) * inv_m[i] - drag[i] * v[i]
        f_prev = f
    if with_jerk:
        i0 = max(k - 1, 0)
        d_prev = 0.0
        if i0 > 0:
            d_prev = dforce(u[i0 - 1] - u[i0], v[i0 - 1] - v[i0], a[i0 - 1] - a[i0],
                             cA[i0 - 1], cg[i0 - 1])
        for i in range(i0, min(k + 3, p)):
            d = dforce(u[i] - u[i + 1], v[i] - v[i + 1], a[i] - a[i + 1], cA[i], cg[i])
            jk[i] = (d_prev - d) * inv_m[i] - drag[i] * a[i]
            d_prev = d


@nb.njit(cache=True, inline="always")
def opening_time(g, r, q, closed):
    # Time until a closed contact opens, from its gap's Taylor quadratic g + r tau + q tau^2 / 2
    # (gap g, rate r, relative acceleration q): the smallest positive root, in a form without
    # cancellation; inf if it does not open on that estimate. Scalars and no branches. (LLVM
    # leaves the min-reduction over contacts scalar, also over padded arrays with fast-math:
    # openings_within spares most steps from it.)
    disc = r * r - 2.0 * q * g
    tau = 2.0 * g / max(np.sqrt(max(disc, 0.0)) - r, 1e-300)
    return tau if (closed > 0.0 and r < 0.0 and disc >= 0.0) else np.inf


@njit_noalias(cache=True, fastmath=FM)
def violated(u1, v1, closed, damp, gam, rate_tol, loading, skip):
    """Whether any contact but ``skip`` is in a violated state at (u1, v1): a gap of the wrong
    sign, or (``loading``) an approach rate of the wrong sign for its dashpot state.

    ``closed``, ``damp`` and ``gam`` are padded to p (zeros past n) like ``cA``, so that the
    branch-free integer count vectorises (see the module notes).
    """
    bad = 0
    for k in range(closed.shape[0]):
        g1 = u1[k] - u1[k + 1]
        r1 = v1[k] - v1[k + 1]
        c = closed[k] > 0.0
        gap = (c & (g1 < 0.0)) | ((closed[k] == 0.0) & (g1 > 0.0))
        rate = (gam[k] > 0.0) & (((damp[k] > 0.0) & (r1 < -rate_tol))
                                 | (c & (damp[k] == 0.0) & (r1 > rate_tol)))
        bad += 1 if ((gap | (loading & rate)) & (k != skip)) else 0
    return bad > 0


@njit_noalias(cache=True, fastmath=FM)
def openings_within(u, v, a, closed, T, flag):
    """Flags (1.0) into ``flag`` (p,) the closed contacts that may open within time T, and
    returns their number: a superset (by a relative margin of 1e-6) of those with
    :func:`opening_time` < T, found without its square root and division (2 g / (sqrt(disc)
    - r) < T <=> 2 g + T r < T sqrt(disc)) so that the pass vectorises; padded ``closed`` as
    in :func:`violated`. Only flagged contacts then need the least time (on the paper chain
    3 steps in 4 have none)."""
    count = 0
    for k in range(closed.shape[0]):
        g = u[k] - u[k + 1]
        r = v[k] - v[k + 1]
        disc = r * r - 2.0 * (a[k] - a[k + 1]) * g
        lhs = 2.0 * g + T * r
        soon = (lhs < 0.0) | (lhs * lhs <= (1.0 + 1e-6) * T * T * disc)
        ok = (closed[k] > 0.0) & (r < 0.0) & (disc >= 0.0) & soon
        flag[k] = 1.0 if ok else 0.0
        count += 1 if ok else 0
    return count


@njit_noalias(cache=True, fastmath=FM)
def switch_candidates(v, a, closed, damp, gam, rate_tol, two_h, flag):
    """Flags (1.0) into ``flag`` (p,) the closed contacts with a dashpot whose approach rate
    is above the noise floor, of the sign their dashpot state allows (not one that just
    switched, within its tolerance) and closing in on zero within ``two_h`` on a linear
    estimate; returns their number. Branch-free over the padded arrays (vectorised); the
    predictor then visits only these."""
    count = 0
    for k in range(closed.shape[0]):
        r = v[k] - v[k + 1]
        q = a[k] - a[k + 1]
        ok = ((closed[k] > 0.0) & (gam[k] > 0.0) & (r * q < 0.0) & (abs(r) > rate_tol)
              & (abs(r) < two_h * abs(q)) & ((r > 0.0) == (damp[k] > 0.0)))
        flag[k] = 1.0 if ok else 0.0
        count += 1 if ok else 0
    return count


@nb.njit(cache=True, inline="always")
def gap_tol(k, closed, damp, gam, hkk):
    # Tolerance of the switch time of contact k's gap state, in steps (see GAP_TOL).
    smooth = hkk or gam[k] == 0.0 or (closed[k] > 0.0 and damp[k] == 0.0)
    return GAP_TOL_SMOOTH if smooth else GAP_TOL


@nb.njit(cache=True)
def switch(kind, k, t, u, v, a, jk, jk_ok, closed, damp, A, gam, cA, cg, law, load, inv_m,
           drag, t_left, q_left, s_left):
    """Switch contact k's state at time t (``kind`` as in :func:`toggle`) and update the
    accelerations (and valid jerks) that change. With the loading law the relative
    accelerations and jerks of the contacts around k just before the first switch at t are
    kept (``q_left``, ``s_left``, ``t_left`` = t) for the switch predictor, and the jerks are
    formed first if not valid. Returns (whether it closed, whether the jerks are valid)."""
    if law == LAW_LINEAR_LOADING:
        if not jk_ok:
            jerks(u, v, a, cA, cg, inv_m, drag, jk)
            jk_ok = True
        # A switch of contact k moves the accelerations of its two particles and the jerks of
        # the four around it: the relative ones of contacts k - 2 .. k + 2.
        for i in range(max(k - 2, 0), min(k + 3, t_left.shape[0])):
            if t_left[i] != t:
                t_left[i] = t
                q_left[i] = a[i] - a[i + 1]
                s_left[i] = jk[i] - jk[i + 1]
    closing = toggle(kind, k, closed, damp, A, gam, cA, cg)
    update_near(k, u, v, a, jk, jk_ok and law != LAW_HKK, cA, cg, law, load, inv_m, drag)
    return closing, jk_ok


@nb.njit(cache=True)
def toggle(kind, k, closed, damp, A, gam, cA, cg):
    """Switch contact k's elastic state (kind 0) or its dashpot (kind 1); True if it closed.

    Updates the coefficient arrays ``cA = closed * A`` and ``cg = damp * gam`` of contact k.
    """
    closed_now = False
    if kind == 1:
        damp[k] = 1.0 - damp[k]
    else:
        closed[k] = 1.0 - closed[k]
        # A contact closes while loading (dashpot on for every law) and opens while unloading
        # (the loading-only dashpot is then already off).
        damp[k] = closed[k]
        closed_now = closed[k] > 0.0
    cA[k] = closed[k] * A[k]
    cg[k] = damp[k] * gam[k]
    return closed_now
