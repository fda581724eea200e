"""Phases of one pass of the chain kernel's step loop (:func:`.stepper.integrate`).

In the order the loop calls them: :func:`nominal_length`, :func:`plan_opening` and
:func:`predict_switch` choose the step's length and time variable; :func:`take_step` runs the
Runge-Kutta step; :func:`earliest_violation` finds a contact state violated at its end, and
:func:`cut_back` redoes the step to that crossing; :func:`prediction_holds` and
:func:`keep_history` serve the dashpot-switch predictor; :func:`output_jerks` and
:func:`dense_output` write the samples inside the step; :func:`switch_at_end` names the
contact that switches at its end. They are inlined into the loop (numba ``inline="always"``),
so the split costs no calls; arrays are passed one by one, not in tuples (building a tuple of
arrays counts references in the step loop).

A variable that starts from a constant and is reassigned later (a contact index starting at
"none", ``np.int64(-1)``; in the loop the sample index ``j`` and the flag ``j0_ok``) starts
from a typed numpy scalar, not a Python literal: numba types a call to a compiled function
as soon as its arguments have *a* type, so ``k = -1`` first compiled each callee (and the
whole step loop, for ``sqrt_start``) for the literal type ``Literal[int](-1)`` and then again
for ``int64``, the type the variable ends with. Those first compilations were never used and
took about a quarter of the kernel's first compilation (measured: chain stage of the main
study with a cold cache 42 s -> 35 s at load 3). The compiled code, and every result, is the
same.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain.kernel.dop853_step import (
    STEP_REGULAR,
    STEP_SQRT_END,
    STEP_SQRT_START,
    rk_step,
)
from msens.chain.kernel.events import (
    NEWTON_MAX,
    PRED_TOL,
    THETA_NOW,
    first_violation,
    gap_tol,
    opening_time,
    openings_within,
    rate_zero,
    switch_candidates,
    violated,
)
from msens.chain.kernel.forces import LAW_LINEAR_LOADING, accelerations, gap, jerks
from msens.chain.kernel.hermite import hermite3
from msens.chain.kernel.sampling import sample, sample_sqrt

#: Longest step taken in sqrt(t0 - t) to an opening, in nominal steps (1/2 errs 1e-6 on the
#: rebound speed of a single Hertz collision at t_c/5, 1/4 6e-9).
END_FRAC = 0.25
#: A step may be stretched by this fraction to end at a predicted dashpot switch.
PRED_STRETCH = 1e-2


@nb.njit(cache=True, inline="always")
def nominal_length(t, dt, sqrt_start, t_close, grade, h_cap):
    """Length of the next step before any event shortens it, s: dt 2^-grade right after a
    closing (the step in sqrt(t - t0)), then at most twice the time since the closing and
    that time plus dt 2^-grade, and at most ``h_cap`` (> 0: a step being redone)."""
    h = dt
    if sqrt_start:
        h = dt / 2.0**grade
    elif t - t_close < dt:
        h = min(dt, 2.0 * (t - t_close), t - t_close + dt / 2.0**grade)
    if h_cap > 0.0:
        h = min(h, h_cap)
    return h


@nb.njit(cache=True, inline="always")
def plan_opening(h, mode, dt, sqrt_start, u, v, a0, closed, flag, n):
    """Shorten the step for a closed contact about to open.

    The least time to an opening, from each gap's Taylor polynomial to second order (its
    smallest positive root, see :func:`msens.chain.kernel.events.opening_time`): within the
    step, the step ends there and is taken in sqrt(t0 - t) (``STEP_SQRT_END``; its length is
    refined by Newton in :func:`take_step`); within two steps, the step goes half-way (each
    step as long as the distance left at its end).

    Returns
    -------
    h : float
        Step length, s.
    mode : int
        Time variable of the step.
    k_open : int
        The contact that opens at the step's end, -1 if none.
    now : bool
        ``k_open`` opens at the step's start (switch it and plan again).
    """
    k_open = np.int64(-1)
    tau_min = 2.0 * h
    if openings_within(u, v, a0, closed, tau_min, flag) > 0:
        for k in range(n):
            if flag[k] > 0.0:
                tau_min = min(tau_min, opening_time(u[k] - u[k + 1], v[k] - v[k + 1],
                                                    a0[k] - a0[k + 1], closed[k]))
    if tau_min < 2.0 * h:
        if not sqrt_start and tau_min > min(h, 1.5 * (END_FRAC * dt)):
            h = 0.5 * tau_min
        elif not sqrt_start:
            # Which contact (a scalar pass, as rare as openings).
            h_open = 2.0 * h
            for k in range(n):
                tau = opening_time(gap(u, k), gap(v, k), gap(a0, k), closed[k])
                if tau < h_open:
                    h_open = tau
                    k_open = k
            if k_open >= 0:
                h = h_open
                mode = STEP_SQRT_END
                return h, mode, k_open, h <= THETA_NOW * dt
        else:
            h = 0.5 * tau_min
    return h, mode, k_open, False


@nb.njit(cache=True, inline="always")
def predict_switch(t, h, mode, k_open, dt, v, a0, j0, closed, damp, gam_p, rate_tol, flag,
                   t_left, q_left, s_left, r_prev, q_prev, s_prev, h_prev, n):
    """Loading law: end the step where a dashpot is predicted to switch.

    The zero of a contact's approach rate, extrapolated from the quintic through the rate
    and its first two derivatives at this and the previous step's start
    (:func:`msens.chain.kernel.events.rate_zero`), instead of stepping past it and redoing
    the step to the crossing. Only the flagged candidates are visited
    (:func:`msens.chain.kernel.events.switch_candidates`); of equal predicted times the
    first wins. ``t_left``, ``q_left``, ``s_left``: the left limits at the latest switch
    nearby (see :func:`msens.chain.kernel.events.switch`); ``r_prev``, ``q_prev``,
    ``s_prev``: the rates and their derivatives at the previous step's start, ``h_prev`` ago
    (:func:`keep_history`).

    Returns
    -------
    h, mode, k_open : float, int, int
        As :func:`plan_opening`'s (a predicted switch before an opening ends the step
        regularly).
    k_pred : int
        The contact whose dashpot switches at the step's end, -1 if none.
    now : bool
        The switch is due at the step's start.
    """
    k_pred = np.int64(-1)
    h_max = h * (1.0 + PRED_STRETCH)
    if switch_candidates(v, a0, closed, damp, gam_p, rate_tol, 2.0 * h, flag) > 0:
        for k in range(n):
            if flag[k] == 0.0:
                continue
            r = gap(v, k)
            q = gap(a0, k)
            sk = gap(j0, k)
            at_switch = t_left[k] == t
            tau = rate_zero(r, q, sk, q_left[k] if at_switch else q,
                            s_left[k] if at_switch else sk, r_prev[k], q_prev[k], s_prev[k],
                            h_prev, 2.0 * h)
            if 0.0 < tau < h_max:
                h_max = tau
                h = tau
                k_pred = k
    if k_pred >= 0 and mode == STEP_SQRT_END:
        # The step now ends before the opening.
        mode = STEP_REGULAR
        k_open = np.int64(-1)
    return h, mode, k_open, k_pred, k_pred >= 0 and h <= PRED_TOL * dt


@nb.njit(cache=True, inline="always")
def take_step(h, mode, k_open, u, v, a0, closed, damp, gam, hkk, cA, cg, load, inv_m, drag, kv,
              tu, tv, u1, v1):
    """The Runge-Kutta step from (u, v) into (u1, v1); one to an opening (``k_open``) is
    refined by Newton on its length until the contact's gap vanishes at its end (if it does
    not open as estimated, it grazes: a regular step of the estimated length, in which an
    opening is found as a violated state).

    Returns
    -------
    h, mode, k_open : float, int, int
        Of the step taken.
    steps : int
        Runge-Kutta steps run.
    """
    h_first = h
    tol = gap_tol(k_open, closed, damp, gam, hkk) if k_open >= 0 else 0.0
    steps = 0
    for it in range(NEWTON_MAX + 2):
        rk_step(u, v, a0, h, mode, cA, cg, hkk, load, inv_m, drag, kv, tu, tv, u1, v1)
        steps += 1
        if k_open < 0:
            break
        g = gap(u1, k_open)
        r = gap(v1, k_open)
        if abs(g) <= tol * h * abs(r):
            break
        hn = h - g / r if r < 0.0 else -1.0
        if it >= NEWTON_MAX or not 0.0 < hn <= 2.0 * h_first:
            mode = STEP_REGULAR
            k_open = np.int64(-1)
            h = h_first
        else:
            h = hn
    return h, mode, k_open, steps


@nb.njit(cache=True, inline="always")
def earliest_violation(h, u, v, a0, u1, v1, a1, closed, damp, gam, gam_p, rate_tol, loading,
                       k_pred, k_open, n):
    """The earliest violated contact state in the step (u, v) -> (u1, v1) of length h.

    A branch-free pass tells whether any state besides the predicted switch ``k_pred`` is
    violated; only then are all contacts scanned (else only ``k_pred``'s). ``k_open`` opens at
    the step's end and is skipped. A predicted switch whose rate keeps its allowed sign at
    1 - ``PRED_TOL`` of the step changes sign at the step's end: no violation.

    Returns
    -------
    kmin : int
        The contact, -1 if none.
    kind : int
        0: its gap (open/closed) state, 1: the sign of its approach rate (dashpot on/off,
        loading law only).
    th_min : float
        The crossing as a fraction of the step (2.0 if none).
    """
    kmin = np.int64(-1)
    kind = 0
    th_min = 2.0
    bad = violated(u1, v1, closed, damp, gam_p, rate_tol, loading, k_pred)
    for k in range(0 if bad else max(k_pred, 0), n if bad else k_pred + 1):
        if k == k_open:
            continue
        g1 = gap(u1, k)
        if (closed[k] > 0.0 and g1 < 0.0) or (closed[k] == 0.0 and g1 > 0.0):
            th = first_violation(gap(u, k), h * gap(v, k), g1, h * gap(v1, k), closed[k] > 0.0)
            if th < th_min:
                th_min = th
                kmin = k
                kind = 0
        elif loading and closed[k] > 0.0 and gam[k] > 0.0:
            # (a contact without dashpot has no dashpot switches to track)
            r1 = gap(v1, k)
            if (damp[k] > 0.0 and r1 < -rate_tol) or (damp[k] == 0.0 and r1 > rate_tol):
                if k == k_pred and hermite3(
                        (1.0 - 2.0 * damp[k]) * gap(v, k),
                        (1.0 - 2.0 * damp[k]) * h * gap(a0, k),
                        (1.0 - 2.0 * damp[k]) * r1, (1.0 - 2.0 * damp[k]) * h * gap(a1, k),
                        1.0 - PRED_TOL) <= 0.0:
                    continue
                th = first_violation(gap(v, k), h * gap(a0, k), r1, h * gap(a1, k),
                                     damp[k] > 0.0)
                if th < th_min:
                    th_min = th
                    kmin = k
                    kind = 1
    return kmin, kind, th_min


@nb.njit(cache=True, inline="always")
def cut_back(h, mode, kmin, kind, th_min, dt, law, u, v, a0, closed, damp, gam, hkk, cA, cg,
             load, inv_m, drag, kv, tu, tv, u1, v1, a1):
    """Redo the step (length h) to the crossing ``th_min`` of contact ``kmin``'s state,
    refined by Newton on the event function (not for a rate switch, ``kind`` 1: only a kink
    of the force, its cubic estimate, error O(h^4), is ample).

    The cut step ends where the contact opens (in sqrt(t0 - t), unless it starts at a
    closing) or switches otherwise (regular). An opening that the estimate missed, far in the
    step, ends this step ``END_FRAC`` dt before it instead (regular; ``kmin`` becomes -1);
    the next one ends at it. With the loading law and no contact at the end, ``a1`` is
    formed for (u1, v1).

    Returns
    -------
    h, mode, k_open : float, int, int
        Of the cut step; (u1, v1) is the state at its end.
    kmin : int
        The contact that switches at its end, -1 if none.
    steps : int
        Runge-Kutta steps run.
    """
    k_open = np.int64(-1)
    opening = kind == 0 and closed[kmin] > 0.0
    if mode != STEP_SQRT_START:
        mode = STEP_SQRT_END if opening else STEP_REGULAR
        k_open = kmin if opening else -1
    h_end = END_FRAC * dt
    hc = th_min * h
    if mode == STEP_SQRT_END and hc > 1.5 * h_end:
        mode = STEP_REGULAR
        hc -= h_end
        kmin = np.int64(-1)
        k_open = np.int64(-1)
    tol = gap_tol(kmin, closed, damp, gam, hkk) if kmin >= 0 else 0.0
    steps = 0
    for it in range(NEWTON_MAX + 1):
        rk_step(u, v, a0, hc, mode, cA, cg, hkk, load, inv_m, drag, kv, tu, tv, u1, v1)
        steps += 1
        if kmin < 0:
            if law == LAW_LINEAR_LOADING:
                accelerations(u1, v1, cA, cg, law, load, inv_m, drag, a1)
            break
        if it == NEWTON_MAX or kind == 1:
            break
        g = gap(u1, kmin)
        r = gap(v1, kmin)
        if abs(g) <= tol * h * abs(r) or r == 0.0:
            break
        hn = hc - g / r
        if hn <= 0.0 or hn > h:
            break
        hc = hn
    return hc, mode, k_open, kmin, steps


@nb.njit(cache=True, inline="always")
def prediction_holds(k_pred, h, v1, a1, damp):
    """Whether the predicted dashpot switch of contact ``k_pred`` is taken at the step's end:
    the rate's zero lies within ``PRED_TOL`` steps of it (either side); otherwise the
    prediction fell short."""
    r1 = gap(v1, k_pred)
    q1 = gap(a1, k_pred)
    crossed = r1 < 0.0 if damp[k_pred] > 0.0 else r1 > 0.0
    return crossed or abs(r1) <= PRED_TOL * h * abs(q1)


@nb.njit(cache=True, inline="always")
def keep_history(v, a0, j0, r_prev, q_prev, s_prev, n):
    """The approach rates and their first two derivatives at the step's start into
    ``r_prev``, ``q_prev``, ``s_prev``, for the next prediction."""
    for k in range(n):
        r_prev[k] = gap(v, k)
        q_prev[k] = gap(a0, k)
        s_prev[k] = gap(j0, k)


@nb.njit(cache=True, inline="always")
def output_jerks(t_out, j, t, h, septic, j0_ok, u, v, a0, j0, u1, v1, a1, j1, cA, cg, inv_m,
                 drag):
    """The jerks at both ends of the step (``j0`` only unless ``j0_ok``) where the septic
    interpolant needs them: the step holds output samples. Returns whether ``j1`` holds
    those at its end."""
    if septic and j < t_out.shape[0] and t_out[j] <= t + h:
        if not j0_ok:
            jerks(u, v, a0, cA, cg, inv_m, drag, j0)
        jerks(u1, v1, a1, cA, cg, inv_m, drag, j1)
        return True
    return False


@nb.njit(cache=True, inline="always")
def dense_output(t_out, j, t, h, dt, mode, law, septic, store_uv, subset, u, v, a0, j0, u1, v1,
                 a1, j1, cA, cg, out_F, out_d, out_u, out_v, sel, us, vs, F, cs):
    """Write the output samples in (t, t + h] (see :mod:`msens.chain.kernel.sampling`) and
    return the next output index.

    (u, v, a0, j0) and (u1, v1, a1, j1): the states, accelerations and jerks at both ends
    (:func:`output_jerks`). Outputs and scratch arrays as in
    :func:`msens.chain.kernel.sampling.sample`. (At most 29 arguments: from 30 on, CPython
    passes them as a tuple, which numba cannot inline.)
    """
    nt = t_out.shape[0]
    if mode == STEP_REGULAR or h < 1e-3 * dt:
        j = sample(t_out, j, t, h, 1e-3 * dt, u, v, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                   store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel, subset)
    elif j < nt and t_out[j] <= t + h:
        j = sample_sqrt(t_out, j, t, h, mode, u, v, a0, j0, u1, v1, a1, j1, cA, cg, law,
                        septic, store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel,
                        subset)
    return j


@nb.njit(cache=True, inline="always")
def switch_at_end(kmin, kind, th_min, k_open, k_pred):
    """The contact whose state switches at the end of the step just taken, and of which
    kind (-1, 0 if none): a crossing the step was cut back to, else an opening it was taken
    to, else a predicted dashpot switch."""
    if kmin >= 0 and th_min > THETA_NOW:
        return kmin, kind
    if k_open >= 0:
        return k_open, 0
    if k_pred >= 0:
        return k_pred, 1
    return -1, 0
