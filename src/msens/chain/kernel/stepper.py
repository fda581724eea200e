"""The chain kernel's step loop: :func:`integrate` (one chain), :func:`integrate_batch`.

Each pass of the loop is one step, in phases (one helper each): choose the step's length and
time variable (:func:`_plan_step`: grading after a closing, an opening foreseen, a dashpot
switch predicted), take the Runge-Kutta step (refined by Newton to an opening), find the
earliest violated contact state and cut the step back to it (:func:`_cut_back`), write the
dense output, then advance and switch the contact whose event ends the step. The scheme is
described in :mod:`msens.chain.kernel`.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain.kernel.dop853_step import (
    N_STAGES,
    STEP_REGULAR,
    STEP_SQRT_END,
    STEP_SQRT_START,
    rk_step,
)
from msens.chain.kernel.events import (
    NEWTON_MAX,
    PRED_TOL,
    THETA_NOW,
    closing_grade,
    first_violation,
    gap_tol,
    opening_time,
    openings_within,
    rate_zero,
    switch,
    switch_candidates,
    violated,
)
from msens.chain.kernel.forces import (
    LAW_HKK,
    LAW_LINEAR_LOADING,
    accelerations,
    gap,
    jerks,
    padded_length,
    zeros64,
    zeros64_rows,
)
from msens.chain.kernel.hermite import hermite3
from msens.chain.kernel.sampling import sample, sample_sqrt

#: Longest step taken in sqrt(t0 - t) to an opening, in nominal steps (1/2 errs 1e-6 on the
#: rebound speed of a single Hertz collision at t_c/5, 1/4 6e-9).
END_FRAC = 0.25
#: A step may be stretched by this fraction to end at a predicted dashpot switch.
PRED_STRETCH = 1e-2


@nb.njit(cache=True)
def integrate(u_init, v_init, mass, A, gam, law, load, t_out, dt, grade_levels, rate_tol,
              store_uv, out_F, out_d, out_u, out_v, sel):
    """Integrate one chain from t = 0 over t_out (sorted, t_out[0] >= 0) with nominal step dt.

    ``grade_levels`` is the depth K of the step grading after a contact closes (first step,
    in sqrt(t - t0), dt 2^-K); ``rate_tol`` (m/s) the approach rate below which a sign change
    of the rate is not an event (the loading-only dashpot then errs by at most
    gamma * rate_tol).

    Fills out_F, out_d with the forces and approaches of the contacts ``sel`` (int64, (c,)),
    each (nt, c): all contacts are ``sel`` = 0, ..., p - 1 with p = n rounded up to a multiple
    of ``PAD`` (columns past n come out 0), through full-width vector loops; any other
    ``sel`` (indices < n) is a subset, sampled contact by contact. With ``store_uv`` also
    out_u, out_v, each (nt, p). Returns the number of steps taken (event cuts and Newton
    re-steps included).
    """
    n = u_init.shape[0]
    p = padded_length(n)  # padded layout (see contact_forces): entries n.. stay 0
    m = p + 1
    subset = sel.shape[0] != p
    for c in range(sel.shape[0]):
        if sel[c] != c:
            subset = True
    for c in range(sel.shape[0] if subset else 0):
        if not 0 <= sel[c] < n:
            raise ValueError("output contacts must be in 0..n-1")
    if out_F.shape[1] != sel.shape[0] or out_d.shape[1] != sel.shape[0] or (store_uv and (
            out_u.shape[1] != p or out_v.shape[1] != p)):
        raise ValueError("out_F, out_d need one column per output contact, out_u, out_v "
                         "padded_length(n)")
    inv_m = zeros64(p)
    inv_m[:n] = 1.0 / mass
    load_p = zeros64(p)
    load_p[:n] = load
    u = zeros64(m)
    v = zeros64(m)
    u[:n] = u_init
    v[:n] = v_init
    u1 = zeros64(m)
    v1 = zeros64(m)
    a0 = zeros64(m)
    a1 = zeros64(m)
    kv = zeros64_rows(N_STAGES, m)
    tu = zeros64(m)
    tv = zeros64(m)
    F = zeros64(m)
    us = zeros64(m)
    cs = zeros64_rows(10, m)
    j0 = zeros64(m)
    j1 = zeros64(m)
    vs = zeros64(m)
    # Loading law: approach rates and their first two derivatives at the start of the
    # previous step (size h_prev), and left limits of the derivatives at the latest switch
    # nearby (time t_left), for predicting dashpot switches.
    r_prev = np.zeros(n)
    q_prev = np.zeros(n)
    s_prev = np.zeros(n)
    t_left = np.full(n, -np.inf)
    q_left = np.zeros(n)
    s_left = np.zeros(n)
    h_prev = 0.0
    # Contact states padded like cA (zeros past n) for the vectorised passes, with a padded
    # copy of gamma and scratch flags. (Rebinding gam to its padded copy made the runs 2-3 %
    # slower, with unchanged results.)
    closed = zeros64(p)
    damp = zeros64(p)
    gam_p = zeros64(p)
    gam_p[:n] = gam
    flag = zeros64(p)
    cA = zeros64(p)
    cg = zeros64(p)
    loading = law == LAW_LINEAR_LOADING
    hkk = law == LAW_HKK
    # Septic dense output from the jerks (the Kuwabara-Kono jerk is unbounded at contact
    # switches: quintic there).
    septic = not hkk
    for k in range(n):
        g = gap(u, k)
        r = gap(v, k)
        closed[k] = 1.0 if (g > 0.0 or (g == 0.0 and r > 0.0)) else 0.0
        # At rest (r = 0) the loading-only dashpot starts on: its force is 0 either way,
        # and the first disturbance (usually compressive) then needs no switch.
        damp[k] = closed[k] * (1.0 if (not loading or r >= 0.0) else 0.0)
        cA[k] = closed[k] * A[k]
        cg[k] = damp[k] * gam[k]
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    accelerations(u, v, cA, cg, law, load_p, inv_m, a0)
    if septic:
        jerks(u, v, a0, cA, cg, inv_m, j0)
    # The jerks are only formed for steps with samples: j0 holds those at the step's start
    # when j0_ok.
    j0_ok = True
    j = 0
    # Samples at the initial time.
    while j < nt and t_out[j] <= 0.0:
        j = sample(t_out, j, -1.0, 1.0, 0.0, u, v, a0, j0, u, v, a0, j0, cA, cg, law, septic,
                    store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel, subset)
    t = 0.0
    steps = 0
    toggles_here = 0
    # Redone steps at this time, and the length the next step may not exceed (0: no cap).
    redo_here = 0
    h_cap = 0.0
    # Whether the next step starts where a contact closed (then taken in sqrt(t - t0), of
    # length dt 2^-grade), and the time of the latest closing: the steps after it are at most
    # as long as the time since plus dt 2^-grade (dt 2^-grade, 2 dt 2^-grade, 4 dt 2^-grade,
    # ...) and twice the time since (should the first step have been cut short), so that
    # its singularity stays at a distance.
    grade = grade_levels
    sqrt_start = False
    t_close = -np.inf
    for k in range(n):
        if closed[k] > 0.0 and gap(u, k) == 0.0:
            sqrt_start = True
            t_close = 0.0
    while j < nt:
        h = dt
        if sqrt_start:
            h = dt / 2.0**grade
        elif t - t_close < dt:
            h = min(dt, 2.0 * (t - t_close), t - t_close + dt / 2.0**grade)
        if h_cap > 0.0:
            h = min(h, h_cap)
        mode = STEP_SQRT_START if sqrt_start else STEP_REGULAR
        # A closed contact about to open: the least time to opening, tau, from the gap's
        # Taylor polynomial to second order (its smallest positive root; branch-free, see
        # opening_time). Opening within the step: the step ends there, taken in
        # sqrt(t0 - t) (the Newton refinement of its length follows the step); within two
        # steps: half-way first.
        tau_min = 2.0 * h
        if openings_within(u, v, a0, closed, tau_min, flag) > 0:
            for k in range(n):
                if flag[k] > 0.0:
                    tau_min = min(tau_min, opening_time(u[k] - u[k + 1], v[k] - v[k + 1],
                                                         a0[k] - a0[k + 1], closed[k]))
        k_open = -1
        h_end = END_FRAC * dt
        if tau_min < 2.0 * h:
            if not sqrt_start and tau_min > min(h, 1.5 * h_end):
                # Approach in halving steps (each as long as the distance left at its end).
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
                if k_open >= 0 and h <= THETA_NOW * dt and toggles_here < 4 * n:
                    # Opening now.
                    toggles_here += 1
                    _, j0_ok = switch(0, k_open, t, u, v, a0, j0, j0_ok, closed, damp, A, gam,
                                       cA, cg, law, load_p, inv_m, t_left, q_left, s_left)
                    continue
            else:
                h = 0.5 * tau_min
        # Loading law: end the step where a dashpot is predicted to switch (the zero of the
        # approach rate, extrapolated from its quintic through this and the previous step's
        # start), instead of stepping past it and redoing the step to the crossing.
        k_pred = -1
        if loading and not j0_ok:
            jerks(u, v, a0, cA, cg, inv_m, j0)
            j0_ok = True
        if loading and h_prev > 0.0:
            h_max = h * (1.0 + PRED_STRETCH)
            # Candidates (see switch_candidates); of equal predicted times the first wins.
            if switch_candidates(v, a0, closed, damp, gam_p, rate_tol, 2.0 * h, flag) > 0:
                for k in range(n):
                    if flag[k] == 0.0:
                        continue
                    r = gap(v, k)
                    q = gap(a0, k)
                    sk = gap(j0, k)
                    left = t_left[k] == t
                    tau = rate_zero(r, q, sk, q_left[k] if left else q,
                                     s_left[k] if left else sk, r_prev[k], q_prev[k],
                                     s_prev[k], h_prev, 2.0 * h)
                    if 0.0 < tau < h_max:
                        h_max = tau
                        h = tau
                        k_pred = k
            if k_pred >= 0 and mode == STEP_SQRT_END:
                # The step now ends before the opening.
                mode = STEP_REGULAR
                k_open = -1
            if k_pred >= 0 and h <= PRED_TOL * dt and toggles_here < 4 * n:
                # The switch is due now.
                toggles_here += 1
                _, j0_ok = switch(1, k_pred, t, u, v, a0, j0, j0_ok, closed, damp, A, gam, cA,
                                   cg, law, load_p, inv_m, t_left, q_left, s_left)
                continue
        if t + h > t_end - 0.01 * dt:
            # Stretch the last step by at most 1% rather than leave a sliver.
            h = t_end - t
            if mode == STEP_SQRT_END:
                mode = STEP_REGULAR
                k_open = -1
        if h <= 0.0:
            h = dt  # only rounding left: finish the last samples with one more step
        # The step; one to an opening (k_open) is refined by Newton on its length until the
        # contact's gap vanishes at its end. (rk_step has two call sites in this function:
        # each inlined copy costs ~4 s of compile time.)
        h_first = h
        tol = gap_tol(k_open, closed, damp, gam, hkk) if k_open >= 0 else 0.0
        for it in range(NEWTON_MAX + 2):
            rk_step(u, v, a0, h, mode, cA, cg, hkk, load_p, inv_m, kv, tu, tv, u1, v1)
            steps += 1
            if k_open < 0:
                break
            g = gap(u1, k_open)
            r = gap(v1, k_open)
            if abs(g) <= tol * h * abs(r):
                break
            hn = h - g / r if r < 0.0 else -1.0
            if it >= NEWTON_MAX or not 0.0 < hn <= 2.0 * h_first:
                # The contact does not open as estimated (it grazes): a regular step of the
                # estimated length; an opening in it is found as a violated state below.
                mode = STEP_REGULAR
                k_open = -1
                h = h_first
            else:
                h = hn
        if loading:
            accelerations(u1, v1, cA, cg, law, load_p, inv_m, a1)
        # Find the earliest violated contact state: kind 0 = gap (open/closed), kind 1 = the
        # sign of the approach rate (dashpot on/off, loading law only).
        kmin = -1
        kind = 0
        th_min = 2.0
        # Any violated state besides the predicted switch? (A branch-free pass; the detailed
        # scan below is rare. The predicted switch's contact alone is checked otherwise.)
        bad = violated(u1, v1, closed, damp, gam_p, rate_tol, loading, k_pred)
        for k in range(0 if bad else max(k_pred, 0), n if bad else k_pred + 1):
            if k == k_open:
                continue  # opens at the step's end (below)
            g1 = gap(u1, k)
            if (closed[k] > 0.0 and g1 < 0.0) or (closed[k] == 0.0 and g1 > 0.0):
                th = first_violation(gap(u, k), h * gap(v, k), g1,
                                      h * gap(v1, k), closed[k] > 0.0)
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
                        # The predicted switch: the rate's sign is still the allowed one at
                        # 1 - PRED_TOL, so it changes at the step's end. Accepted below.
                        continue
                    th = first_violation(gap(v, k), h * gap(a0, k), r1,
                                          h * gap(a1, k), damp[k] > 0.0)
                    if th < th_min:
                        th_min = th
                        kmin = k
                        kind = 1
        if kmin >= 0:
            if th_min <= THETA_NOW and toggles_here < 4 * n:
                # The contact changes state now: toggle and redo the step.
                toggles_here += 1
                closing, j0_ok = switch(kind, kmin, t, u, v, a0, j0, j0_ok, closed, damp, A,
                                         gam, cA, cg, law, load_p, inv_m, t_left, q_left,
                                         s_left)
                if closing:
                    sqrt_start = True
                    t_close = t
                    grade = closing_grade(gap(v, kmin) * dt, gap(a0, kmin) * dt * dt,
                                           grade_levels)
                continue
            if th_min > THETA_NOW:
                # Cut the step back to the crossing; refine by Newton on the event function.
                # The cut step ends where contact kmin opens (in sqrt(t0 - t), unless it
                # starts at a closing) or switches otherwise (regular).
                k_open = -1
                opening = kind == 0 and closed[kmin] > 0.0
                if mode != STEP_SQRT_START:
                    mode = STEP_SQRT_END if opening else STEP_REGULAR
                    k_open = kmin if opening else -1
                hc = th_min * h
                if mode == STEP_SQRT_END and hc > 1.5 * h_end:
                    # An opening that the estimate missed, far in the step: end this step
                    # h_end before it instead (regular); the next one ends at it.
                    mode = STEP_REGULAR
                    hc -= h_end
                    kmin = -1
                    k_open = -1
                tol = gap_tol(kmin, closed, damp, gam, hkk) if kmin >= 0 else 0.0
                for it in range(NEWTON_MAX + 1):
                    rk_step(u, v, a0, hc, mode, cA, cg, hkk, load_p, inv_m, kv, tu, tv, u1,
                            v1)
                    steps += 1
                    if kmin < 0:
                        if loading:
                            accelerations(u1, v1, cA, cg, law, load_p, inv_m, a1)
                        break
                    if it == NEWTON_MAX or kind == 1:
                        # A rate switch is only a kink of the force: the cubic estimate of its
                        # time (error O(h^4)) is ample, no Newton refinement.
                        break
                    g = gap(u1, kmin)
                    r = gap(v1, kmin)
                    if abs(g) <= tol * h * abs(r) or r == 0.0:
                        break
                    hn = hc - g / r
                    if hn <= 0.0 or hn > h:
                        break
                    hc = hn
                # (u1, v1) is the state at t + hc.
                h = hc
                if redo_here < 4 and violated(u1, v1, closed, damp, gam_p, rate_tol, loading,
                                               kmin):
                    # Another contact switches before this one, its crossing hidden at the
                    # uncut step's end (it switched there and back): redo the step to here,
                    # which finds it.
                    redo_here += 1
                    h_cap = h
                    continue
        if not (loading and kmin < 0):  # else a1 is already that of (u1, v1)
            accelerations(u1, v1, cA, cg, law, load_p, inv_m, a1)
        if k_pred >= 0 and kmin < 0:
            # The predicted switch is taken at the step's end if the rate's zero lies within
            # PRED_TOL steps of it (either side); otherwise the prediction fell short.
            r1 = gap(v1, k_pred)
            q1 = gap(a1, k_pred)
            crossed = r1 < 0.0 if damp[k_pred] > 0.0 else r1 > 0.0
            if not (crossed or abs(r1) <= PRED_TOL * h * abs(q1)):
                k_pred = -1
        else:
            k_pred = -1
        if loading:
            for k in range(n):
                r_prev[k] = gap(v, k)
                q_prev[k] = gap(a0, k)
                s_prev[k] = gap(j0, k)
            h_prev = h
        j1_ok = False
        if septic and j < nt and t_out[j] <= t + h:
            if not j0_ok:
                jerks(u, v, a0, cA, cg, inv_m, j0)
            jerks(u1, v1, a1, cA, cg, inv_m, j1)
            j1_ok = True
        if mode == STEP_REGULAR or h < 1e-3 * dt:
            j = sample(t_out, j, t, h, 1e-3 * dt, u, v, a0, j0, u1, v1, a1, j1, cA, cg, law,
                        septic, store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel,
                        subset)
        elif j < nt and t_out[j] <= t + h:
            j = sample_sqrt(t_out, j, t, h, mode, u, v, a0, j0, u1, v1, a1, j1, cA, cg, law,
                             septic, store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel,
                             subset)
        t += h
        sqrt_start = False
        u, u1 = u1, u
        v, v1 = v1, v
        toggles_here = 0
        redo_here = 0
        h_cap = 0.0
        a0, a1 = a1, a0
        j0, j1 = j1, j0
        j0_ok = j1_ok
        # A contact switching at the step's end: which, and of which kind.
        k_tog = -1
        kind_tog = 0
        if kmin >= 0 and th_min > THETA_NOW:
            k_tog = kmin
            kind_tog = kind
        elif k_open >= 0:
            k_tog = k_open
        elif k_pred >= 0:
            k_tog = k_pred
            kind_tog = 1
        if k_tog >= 0:
            sqrt_start, j0_ok = switch(kind_tog, k_tog, t, u, v, a0, j0, j0_ok, closed, damp, A,
                                        gam, cA, cg, law, load_p, inv_m, t_left, q_left, s_left)
            if sqrt_start:
                t_close = t
                grade = closing_grade(gap(v, k_tog) * dt, gap(a0, k_tog) * dt * dt,
                                       grade_levels)
    return steps


@nb.njit(cache=True, parallel=True)
def integrate_batch(u_init, v_init, mass, A, gam, law, load, t_out, dt, grade_levels, rate_tol,
                    out_F, out_d, sel):
    """Integrate ``runs`` chains in parallel; arrays carry a leading run axis.

    dt has shape (runs,); ``sel``, the output contacts, is common (see :func:`integrate`).
    Returns the number of steps of each run.
    """
    runs = u_init.shape[0]
    n = u_init.shape[1]
    steps = np.zeros(runs, dtype=np.int64)
    dummy = np.empty((1, n))
    for r in nb.prange(runs):
        steps[r] = integrate(u_init[r], v_init[r], mass[r], A[r], gam[r], law, load[r],
                             t_out, dt[r], grade_levels, rate_tol[r], False, out_F[r], out_d[r],
                             dummy, dummy, sel)
    return steps
