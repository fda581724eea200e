"""The chain kernel's step loop: :func:`integrate` (one chain), :func:`integrate_batch`.

Each pass of the loop is one step, in phases (:mod:`msens.chain.kernel.phases`): choose the
step's length and time variable, take the Runge-Kutta step, find the earliest violated
contact state and cut the step back to it, write the dense output, then advance and switch
the contact whose event ends the step. A contact that switches at the step's start is
switched and the pass starts over. The scheme is described in :mod:`msens.chain.kernel`.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain.kernel.dop853_step import N_STAGES, STEP_REGULAR, STEP_SQRT_END, STEP_SQRT_START
from msens.chain.kernel.events import THETA_NOW, closing_grade, switch, violated
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
from msens.chain.kernel.phases import (
    cut_back,
    dense_output,
    earliest_violation,
    keep_history,
    nominal_length,
    output_jerks,
    plan_opening,
    predict_switch,
    prediction_holds,
    switch_at_end,
    take_step,
)
from msens.chain.kernel.sampling import sample


@nb.njit(cache=True, inline="always")
def _output_subset(sel, n, p, out_F, out_d, out_u, out_v, store_uv):
    """Whether ``sel`` is a subset of the contacts (else all p padded columns in order),
    after checking it and the output arrays' widths."""
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
    return subset


@nb.njit(cache=True, inline="always")
def _pad(u_init, v_init, mass, A, gam, drag, load, u, v, inv_m, drag_m, load_p, gam_p):
    """The particle arrays into the padded ones (zeros past n), with inverse masses and drag
    over mass. Loops, not slice assignments: those compile numba's shape-mismatch error
    message (string formatting, ~2.5 s of the kernel's first compilation)."""
    n = u_init.shape[0]
    if (v_init.shape[0] != n or mass.shape[0] != n or A.shape[0] != n or gam.shape[0] != n
            or drag.shape[0] != n or load.shape[0] != n):
        raise ValueError("u_init, v_init, mass, A, gam, drag, load need one entry per "
                         "particle (contact)")
    for k in range(n):
        inv_m[k] = 1.0 / mass[k]
        drag_m[k] = drag[k] / mass[k]
        load_p[k] = load[k]
        u[k] = u_init[k]
        v[k] = v_init[k]
        gam_p[k] = gam[k]


@nb.njit(cache=True, inline="always")
def _initial_states(u, v, A, gam, loading, n, closed, damp, cA, cg):
    """Contact states at t = 0 into ``closed``, ``damp``, ``cA``, ``cg``; returns whether a
    contact closes exactly at t = 0 (the first step is then taken in sqrt(t))."""
    touching = np.bool_(False)  # not a literal (see msens.chain.kernel.phases)
    for k in range(n):
        g = gap(u, k)
        r = gap(v, k)
        closed[k] = 1.0 if (g > 0.0 or (g == 0.0 and r > 0.0)) else 0.0
        # At rest (r = 0) the loading-only dashpot starts on: its force is 0 either way,
        # and the first disturbance (usually compressive) then needs no switch.
        damp[k] = closed[k] * (1.0 if (not loading or r >= 0.0) else 0.0)
        cA[k] = closed[k] * A[k]
        cg[k] = damp[k] * gam[k]
    for k in range(n):
        if closed[k] > 0.0 and gap(u, k) == 0.0:
            touching = True
    return touching


@nb.njit(cache=True)
def integrate(u_init, v_init, mass, A, gam, drag, law, load, t_out, dt, grade_levels, rate_tol,
              store_uv, out_F, out_d, out_u, out_v, sel):
    """Integrate one chain from t = 0 over t_out (sorted, t_out[0] >= 0) with nominal step dt.

    ``drag`` (n,) is each particle's viscous drag coefficient on the tube, N s/m (force
    -drag v on the particle).

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
    p = padded_length(n)  # padded layout (see msens.chain.kernel.forces): entries n.. stay 0
    m = p + 1
    subset = _output_subset(sel, n, p, out_F, out_d, out_u, out_v, store_uv)
    inv_m = zeros64(p)
    drag_m = zeros64(p)
    load_p = zeros64(p)
    u = zeros64(m)
    v = zeros64(m)
    gam_p = zeros64(p)
    _pad(u_init, v_init, mass, A, gam, drag, load, u, v, inv_m, drag_m, load_p, gam_p)
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
    # Contact states padded like cA (zeros past n) for the vectorised passes, with a padded
    # copy of gamma and scratch flags (gam itself stays unpadded: measured faster).
    closed = zeros64(p)
    damp = zeros64(p)
    flag = zeros64(p)
    cA = zeros64(p)
    cg = zeros64(p)
    sqrt_start = _initial_states(u, v, A, gam, law == LAW_LINEAR_LOADING, n, closed, damp, cA,
                                 cg)
    return _step_loop(t_out, dt, grade_levels, rate_tol, law, store_uv, subset, sqrt_start, n,
                      (u, v, u1, v1, a0, a1, j0, j1, kv, tu, tv, F, us, vs, cs),
                      (closed, damp, A, gam, gam_p, flag, cA, cg, load_p, inv_m, drag_m),
                      (r_prev, q_prev, s_prev, t_left, q_left, s_left),
                      (out_F, out_d, out_u, out_v, sel))


@nb.njit(cache=True, _nrt=False)
def _step_loop(t_out, dt, grade_levels, rate_tol, law, store_uv, subset, sqrt_start, n, work,
               contacts, history, out):
    """The step loop of :func:`integrate` on its allocated arrays; returns the steps taken.

    ``work`` = (u, v, u1, v1, a0, a1, j0, j1, kv, tu, tv, F, us, vs, cs): states at the two
    ends of a step, their accelerations and jerks, Runge-Kutta and sampling scratch;
    ``contacts`` = (closed, damp, A, gam, gam_p, flag, cA, cg, load_p, inv_m, drag_m): contact
    states, coefficients and the particles' loads, inverse masses and drag over mass (1/s)
    (padded layout);
    ``history`` = (r_prev, q_prev, s_prev, t_left, q_left, s_left): the dashpot-switch
    predictor's data; ``out`` = (out_F, out_d, out_u, out_v, sel). ``sqrt_start``: a contact
    closes at t = 0.

    Compiled without reference counting (it allocates nothing): the phase helpers inlined
    into the loop would otherwise count references to every array they are passed, at
    every step (~10 % of the run time).
    """
    u, v, u1, v1, a0, a1, j0, j1, kv, tu, tv, F, us, vs, cs = work
    closed, damp, A, gam, gam_p, flag, cA, cg, load_p, inv_m, drag_m = contacts
    r_prev, q_prev, s_prev, t_left, q_left, s_left = history
    out_F, out_d, out_u, out_v, sel = out
    h_prev = 0.0
    loading = law == LAW_LINEAR_LOADING
    hkk = law == LAW_HKK
    # Septic dense output from the jerks (the Kuwabara-Kono jerk is unbounded at contact
    # switches: quintic there).
    septic = not hkk
    # Whether the next step starts where a contact closed (then taken in sqrt(t - t0), of
    # length dt 2^-grade), and the time of the latest closing (see nominal_length).
    t_close = 0.0 if sqrt_start else -np.inf
    grade = grade_levels
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    accelerations(u, v, cA, cg, law, load_p, inv_m, drag_m, a0)
    if septic:
        jerks(u, v, a0, cA, cg, inv_m, drag_m, j0)
    # The jerks are only formed for steps with samples: j0 holds those at the step's start
    # when j0_ok. (Typed starting values, not literals: see msens.chain.kernel.phases.)
    j0_ok = np.bool_(True)
    j = np.int64(0)
    # Samples at the initial time.
    while j < nt and t_out[j] <= 0.0:
        j = sample(t_out, j, -1.0, 1.0, 0.0, u, v, a0, j0, u, v, a0, j0, cA, cg, law, septic,
                   store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel, subset)
    t = 0.0
    steps = 0
    # Switches at this time (bounded: no endless toggling), redone steps at this time, and
    # the length the next step may not exceed (0: no cap).
    toggles_here = 0
    redo_here = 0
    h_cap = 0.0
    while j < nt:
        h = nominal_length(t, dt, sqrt_start, t_close, grade, h_cap)
        mode = STEP_SQRT_START if sqrt_start else STEP_REGULAR
        h, mode, k_open, now = plan_opening(h, mode, dt, sqrt_start, u, v, a0, closed, flag, n)
        if now and toggles_here < 4 * n:
            toggles_here += 1
            _, j0_ok = switch(0, k_open, t, u, v, a0, j0, j0_ok, closed, damp, A, gam, cA, cg,
                              law, load_p, inv_m, drag_m, t_left, q_left, s_left)
            continue
        k_pred = np.int64(-1)
        if loading and not j0_ok:
            jerks(u, v, a0, cA, cg, inv_m, drag_m, j0)
            j0_ok = True
        if loading and h_prev > 0.0:
            h, mode, k_open, k_pred, now = predict_switch(
                t, h, mode, k_open, dt, v, a0, j0, closed, damp, gam_p, rate_tol, flag,
                t_left, q_left, s_left, r_prev, q_prev, s_prev, h_prev, n)
            if now and toggles_here < 4 * n:
                toggles_here += 1
                _, j0_ok = switch(1, k_pred, t, u, v, a0, j0, j0_ok, closed, damp, A, gam, cA,
                                  cg, law, load_p, inv_m, drag_m, t_left, q_left, s_left)
                continue
        if t + h > t_end - 0.01 * dt:
            # Stretch the last step by at most 1% rather than leave a sliver.
            h = t_end - t
            if mode == STEP_SQRT_END:
                mode = STEP_REGULAR
                k_open = np.int64(-1)
        if h <= 0.0:
            h = dt  # only rounding left: finish the last samples with one more step
        h, mode, k_open, taken = take_step(h, mode, k_open, u, v, a0, closed, damp, gam, hkk,
                                           cA, cg, load_p, inv_m, drag_m, kv, tu, tv, u1, v1)
        steps += taken
        if loading:
            accelerations(u1, v1, cA, cg, law, load_p, inv_m, drag_m, a1)
        kmin, kind, th_min = earliest_violation(h, u, v, a0, u1, v1, a1, closed, damp, gam,
                                                gam_p, rate_tol, loading, k_pred, k_open, n)
        if kmin >= 0 and th_min <= THETA_NOW and toggles_here < 4 * n:
            # The contact changes state now: toggle and redo the step.
            toggles_here += 1
            closing, j0_ok = switch(kind, kmin, t, u, v, a0, j0, j0_ok, closed, damp, A, gam,
                                    cA, cg, law, load_p, inv_m, drag_m, t_left, q_left, s_left)
            if closing:
                sqrt_start = True
                t_close = t
                grade = closing_grade(gap(v, kmin) * dt, gap(a0, kmin) * dt * dt,
                                      grade_levels)
            continue
        if kmin >= 0 and th_min > THETA_NOW:
            h, mode, k_open, kmin, taken = cut_back(h, mode, kmin, kind, th_min, dt, law, u, v,
                                                    a0, closed, damp, gam, hkk, cA, cg, load_p,
                                                    inv_m, drag_m, kv, tu, tv, u1, v1, a1)
            steps += taken
            if redo_here < 4 and violated(u1, v1, closed, damp, gam_p, rate_tol, loading,
                                          kmin):
                # Another contact switches before this one, its crossing hidden at the
                # uncut step's end (it switched there and back): redo the step to here,
                # which finds it.
                redo_here += 1
                h_cap = h
                continue
        if not (loading and kmin < 0):  # else a1 is already that of (u1, v1)
            accelerations(u1, v1, cA, cg, law, load_p, inv_m, drag_m, a1)
        if not (k_pred >= 0 and kmin < 0 and prediction_holds(k_pred, h, v1, a1, damp)):
            k_pred = np.int64(-1)
        if loading:
            keep_history(v, a0, j0, r_prev, q_prev, s_prev, n)
            h_prev = h
        j1_ok = output_jerks(t_out, j, t, h, septic, j0_ok, u, v, a0, j0, u1, v1, a1, j1, cA, cg,
                             inv_m, drag_m)
        j = dense_output(t_out, j, t, h, dt, mode, law, septic, store_uv, subset, u, v, a0, j0,
                         u1, v1, a1, j1, cA, cg, out_F, out_d, out_u, out_v, sel, us, vs, F, cs)
        t += h
        sqrt_start = False
        u, u1 = u1, u
        v, v1 = v1, v
        a0, a1 = a1, a0
        j0, j1 = j1, j0
        j0_ok = j1_ok
        toggles_here = 0
        redo_here = 0
        h_cap = 0.0
        k_tog, kind_tog = switch_at_end(kmin, kind, th_min, k_open, k_pred)
        if k_tog >= 0:
            sqrt_start, j0_ok = switch(kind_tog, k_tog, t, u, v, a0, j0, j0_ok, closed, damp, A,
                                       gam, cA, cg, law, load_p, inv_m, drag_m, t_left, q_left,
                                       s_left)
            if sqrt_start:
                t_close = t
                grade = closing_grade(gap(v, k_tog) * dt, gap(a0, k_tog) * dt * dt,
                                      grade_levels)
    return steps


@nb.njit(cache=True, parallel=True)
def integrate_batch(u_init, v_init, mass, A, gam, drag, law, load, t_out, dt, grade_levels,
                    rate_tol, out_F, out_d, sel):
    """Integrate ``runs`` chains in parallel; arrays carry a leading run axis.

    dt has shape (runs,); ``sel``, the output contacts, is common (see :func:`integrate`).
    Returns the number of steps of each run.
    """
    runs = u_init.shape[0]
    n = u_init.shape[1]
    steps = np.zeros(runs, dtype=np.int64)
    dummy = np.empty((1, n))
    for r in nb.prange(runs):
        steps[r] = integrate(u_init[r], v_init[r], mass[r], A[r], gam[r], drag[r], law, load[r],
                             t_out, dt[r], grade_levels, rate_tol[r], False, out_F[r], out_d[r],
                             dummy, dummy, sel)
    return steps
