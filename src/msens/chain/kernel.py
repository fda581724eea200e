"""Compiled (numba) integrator of the chain: fixed-step 8th-order Runge-Kutta with contact
events.

Scheme
------
The right-hand side of Eq. 6 is smooth only while the set of closed contacts is fixed: a
linear dashpot switches on with a jump at contact (gamma d(delta)/dt != 0 at delta = 0) and
the Hertz force A delta^{3/2} is only C^1 at delta = 0. A fixed-step Runge-Kutta method
stepping across such points loses its order (to O(h) for the jump). We therefore integrate
a *hybrid* system: each contact carries an open/closed state that is frozen during a step,
and a step whose end violates a state (a closed contact with delta < 0 or an open one with
delta > 0) is cut back to the crossing. The crossing time is located on the cubic Hermite
interpolant of the gap (values and rates at both ends), then refined by Newton steps that
re-run the RK step to the new end until the residual gap is below ``1e-7 h |d(gap)/dt|``;
the contact is toggled there and the step sequence resumes with the nominal step.

Even with exact switch times, F ~ (t - t_0)^{3/2} near a switch is not smooth, which would cap
the order at 2.5. Steps are therefore graded geometrically next to switches: after a contact
closes the next steps are dt 2^-K, dt 2^-K, dt 2^-(K-1), ..., dt/2 (K = ``grade_levels``), and a
contact about to open (gap / closing rate < 2 dt) is approached in halving steps. This
restores the high order in practice (see tests/chain/test_integrate.py).

With the loading-only dashpot (``LAW_LINEAR_LOADING``) the dashpot of a closed contact is a
second state, switched where the approach rate changes sign (a kink of the force), located
on the cubic Hermite interpolant of the rate (values and relative accelerations) without
Newton refinement: an O(h^4) error in the time of a kink is harmless. Rates below
``rate_tol`` do not switch it, so the resting part of the chain does not chatter.

The Runge-Kutta method is the 12-stage 8th-order formula of Dormand & Prince (DOP853,
Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., Springer 1993, §II.5), run at a fixed
step; its coefficients are read from SciPy (``scipy.integrate._ivp.dop853_coefficients``,
a private module, stable since SciPy 1.4) so that they are not retyped here.

All functions are compiled with ``cache=True`` (first call ~5 s, then loaded from the cache).

Output at arbitrary times uses the quintic Hermite interpolant of u through (u, v, a) at the
two ends of the step that contains the time (error O(h^6) in u, O(h^5) in v), and the
contact forces are evaluated from the interpolated state with the step's contact states.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _dop

N_STAGES = _dop.N_STAGES
RK_A = np.ascontiguousarray(_dop.A[:N_STAGES, :N_STAGES], dtype=np.float64)
RK_B = np.ascontiguousarray(_dop.B, dtype=np.float64)
#: Order of the Runge-Kutta formula.
RK_ORDER = 8

LAW_LINEAR = 0
LAW_HKK = 1
LAW_LINEAR_LOADING = 2

# A contact whose crossing falls within this fraction of a step from its start toggles at once.
_THETA_NOW = 1e-9
# Newton refinement of a crossing stops when |gap| < _GAP_TOL * h * |d(gap)/dt|.
_GAP_TOL = 1e-7
_NEWTON_MAX = 4


_FM = {"contract"}  # allow fused multiply-add only; no reassociation


@nb.njit(cache=True, fastmath=_FM)
def contact_forces(u, v, A, gam, law, closed, damp, out):
    """Contact forces (N) into ``out`` for displacements ``u`` and velocities ``v``.

    ``closed`` (elastic part on) and ``damp`` (dashpot on) are 1.0 or 0.0 per contact
    (floats so that the loop vectorises without branches).
    """
    n = u.shape[0]
    if law == LAW_HKK:
        for k in range(n - 1):
            dp = max(u[k] - u[k + 1], 0.0)
            out[k] = np.sqrt(dp) * (closed[k] * A[k] * dp + damp[k] * gam[k] * (v[k] - v[k + 1]))
        dp = max(u[n - 1], 0.0)
        out[n - 1] = np.sqrt(dp) * (closed[n - 1] * A[n - 1] * dp
                                    + damp[n - 1] * gam[n - 1] * v[n - 1])
    else:
        for k in range(n - 1):
            dp = max(u[k] - u[k + 1], 0.0)
            out[k] = closed[k] * A[k] * dp * np.sqrt(dp) + damp[k] * gam[k] * (v[k] - v[k + 1])
        dp = max(u[n - 1], 0.0)
        out[n - 1] = (closed[n - 1] * A[n - 1] * dp * np.sqrt(dp)
                      + damp[n - 1] * gam[n - 1] * v[n - 1])


@nb.njit(cache=True, fastmath=_FM)
def accelerations(u, v, A, gam, law, closed, damp, load, inv_m, F, out):
    """Accelerations (m/s^2) into ``out``; ``F`` receives the contact forces."""
    n = u.shape[0]
    contact_forces(u, v, A, gam, law, closed, damp, F)
    out[0] = (load[0] - F[0]) * inv_m[0]
    for i in range(1, n):
        out[i] = (load[i] + F[i - 1] - F[i]) * inv_m[i]


@nb.njit(cache=True, fastmath=_FM)
def rk_step(u, v, a0, h, A, gam, law, closed, damp, load, inv_m, ku, kv, tu, F, u1, v1):
    """One DOP853 step of size ``h`` from (u, v) with a0 = acceleration at (u, v).

    ``ku[s]`` holds the stage velocities (the derivative of u), ``kv[s]`` the stage
    accelerations; ``tu`` is scratch for the stage displacements (``tv`` is unused).
    """
    n = u.shape[0]
    for i in range(n):
        ku[0, i] = v[i]
        kv[0, i] = a0[i]
    for s in range(1, N_STAGES):
        for i in range(n):
            tu[i] = u[i]
            ku[s, i] = v[i]
        for j in range(s):
            c = h * RK_A[s, j]
            if c != 0.0:
                for i in range(n):
                    tu[i] += c * ku[j, i]
                    ku[s, i] += c * kv[j, i]
        accelerations(tu, ku[s], A, gam, law, closed, damp, load, inv_m, F, kv[s])
    for i in range(n):
        u1[i] = u[i]
        v1[i] = v[i]
    for s in range(N_STAGES):
        b = h * RK_B[s]
        if b != 0.0:
            for i in range(n):
                u1[i] += b * ku[s, i]
                v1[i] += b * kv[s, i]


@nb.njit(cache=True, inline="always")
def _gap(x, k, n):
    if k < n - 1:
        return x[k] - x[k + 1]
    return x[k]


@nb.njit(cache=True)
def _first_violation(g0, r0, g1, r1, closed):
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
        return 0.0
    # Bracket the first sign change on a coarse grid, then bisect.
    lo = 0.0
    hi = 1.0
    m = 16
    for j in range(1, m + 1):
        th = j / m
        if _hermite3(p0, d0, p1, d1, th) > 0.0:
            hi = th
            lo = (j - 1) / m
            break
    for _ in range(60):
        if hi - lo < 1e-13:
            break
        mid = 0.5 * (lo + hi)
        if _hermite3(p0, d0, p1, d1, mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return hi


@nb.njit(cache=True, inline="always")
def _hermite3(p0, d0, p1, d1, t):
    t2 = t * t
    t3 = t2 * t
    return ((2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * d0
            + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * d1)


@nb.njit(cache=True)
def _sample(t_out, j, t0, h, tiny, u0, v0, a0, u1, v1, a1, A, gam, law, closed, damp,
            store_uv,
            out_F, out_d, out_u, out_v, us, vs, F):
    """Write the quintic-Hermite samples with t0 < t_out[j] <= t0 + h; return the next j."""
    n = u0.shape[0]
    nt = t_out.shape[0]
    while j < nt and t_out[j] <= t0 + h:
        s = (t_out[j] - t0) / h
        s2 = s * s
        s3 = s2 * s
        s4 = s3 * s
        s5 = s4 * s
        # Quintic Hermite basis on [0, 1] and its derivative.
        h10 = s - 6 * s3 + 8 * s4 - 3 * s5
        h20 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5
        h01 = 10 * s3 - 15 * s4 + 6 * s5
        h11 = -4 * s3 + 7 * s4 - 3 * s5
        h21 = 0.5 * s3 - s4 + 0.5 * s5
        e10 = 1 - 18 * s2 + 32 * s3 - 15 * s4
        e20 = s - 4.5 * s2 + 6 * s3 - 2.5 * s4
        e01 = 30 * s2 - 60 * s3 + 30 * s4
        e11 = -12 * s2 + 28 * s3 - 15 * s4
        e21 = 1.5 * s2 - 4 * s3 + 2.5 * s4
        hh = h * h
        if h < tiny:
            # A sliver step (cut at a contact event): Taylor from the left end, error O(h^3);
            # the Hermite form would divide rounding noise of u1 - u0 by h.
            tau = t_out[j] - t0
            for i in range(n):
                us[i] = u0[i] + tau * (v0[i] + 0.5 * tau * a0[i])
                vs[i] = v0[i] + tau * a0[i]
        else:
            for i in range(n):
                # h00 + h01 = 1 and e00 = -e01: written with u1 - u0 to limit cancellation.
                du = u1[i] - u0[i]
                us[i] = (u0[i] + h01 * du + h10 * h * v0[i] + h20 * hh * a0[i]
                         + h11 * h * v1[i] + h21 * hh * a1[i])
                vs[i] = (e01 * du / h + e10 * v0[i] + e20 * h * a0[i]
                         + e11 * v1[i] + e21 * h * a1[i])
        contact_forces(us, vs, A, gam, law, closed, damp, F)
        for k in range(n):
            out_F[j, k] = F[k]
            g = _gap(us, k, n)
            out_d[j, k] = g if g > 0.0 else 0.0
            if store_uv:
                out_u[j, k] = us[k]
                out_v[j, k] = vs[k]
        j += 1
    return j


@nb.njit(cache=True)
def _toggle(kind, k, closed, damp):
    """Switch contact k's elastic state (kind 0) or its dashpot (kind 1); True if it closed."""
    if kind == 1:
        damp[k] = 1.0 - damp[k]
        return False
    closed[k] = 1.0 - closed[k]
    # A contact closes while loading (dashpot on for every law) and opens while unloading
    # (the loading-only dashpot is then already off).
    damp[k] = closed[k]
    return closed[k] > 0.0


@nb.njit(cache=True)
def integrate(u_init, v_init, mass, A, gam, law, load, t_out, dt, grade_levels, rate_tol,
              store_uv, out_F, out_d, out_u, out_v):
    """Integrate one chain from t = 0 over t_out (sorted, t_out[0] >= 0) with nominal step dt.

    ``grade_levels`` is the depth K of the step grading at contact switches; ``rate_tol``
    (m/s) the approach rate below which a sign change of the rate is not an event (the
    loading-only dashpot then errs by at most gamma * rate_tol).

    Fills out_F, out_d (and out_u, out_v if ``store_uv``), each (nt, n). Returns the
    number of steps taken (event cuts and Newton re-steps included).
    """
    n = u_init.shape[0]
    inv_m = 1.0 / mass
    u = u_init.copy()
    v = v_init.copy()
    u1 = np.empty(n)
    v1 = np.empty(n)
    a0 = np.empty(n)
    a1 = np.empty(n)
    ku = np.empty((N_STAGES, n))
    kv = np.empty((N_STAGES, n))
    tu = np.empty(n)
    F = np.empty(n)
    us = np.empty(n)
    vs = np.empty(n)
    closed = np.zeros(n)
    damp = np.zeros(n)
    loading = law == LAW_LINEAR_LOADING
    for k in range(n):
        g = _gap(u, k, n)
        r = _gap(v, k, n)
        closed[k] = 1.0 if (g > 0.0 or (g == 0.0 and r > 0.0)) else 0.0
        damp[k] = closed[k] * (1.0 if (not loading or r > 0.0) else 0.0)
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    accelerations(u, v, A, gam, law, closed, damp, load, inv_m, F, a0)
    j = 0
    # Samples at the initial time.
    while j < nt and t_out[j] <= 0.0:
        j = _sample(t_out, j, -1.0, 1.0, 0.0, u, v, a0, u, v, a0, A, gam, law, closed, damp,
                    store_uv, out_F, out_d, out_u, out_v, us, vs, F)
    t = 0.0
    steps = 0
    toggles_here = 0
    h_floor = dt / 2.0**grade_levels
    # Steps left in a geometric grading after a contact closed (sizes dt 2^-min(grade, K)).
    grade = 0
    for k in range(n):
        if closed[k] > 0.0 and _gap(u, k, n) == 0.0:
            grade = grade_levels + 1
    while j < nt:
        h = dt
        if grade > 0:
            h = dt / 2.0 ** min(grade, grade_levels)
        else:
            # Approach a closed contact that is about to open in halving steps.
            for k in range(n):
                if closed[k] > 0.0:
                    r = _gap(v, k, n)
                    if r < 0.0:
                        tau = -_gap(u, k, n) / r
                        if 2.0 * h_floor < tau < 2.0 * h:
                            h = 0.5 * tau
        if t + h > t_end - 0.01 * dt:
            # Stretch the last step by at most 1% rather than leave a sliver.
            h = t_end - t
        if h <= 0.0:
            h = dt  # only rounding left: finish the last samples with one more step
        rk_step(u, v, a0, h, A, gam, law, closed, damp, load, inv_m, ku, kv, tu, F, u1, v1)
        steps += 1
        if loading:
            accelerations(u1, v1, A, gam, law, closed, damp, load, inv_m, F, a1)
        # Find the earliest violated contact state: kind 0 = gap (open/closed), kind 1 = the
        # sign of the approach rate (dashpot on/off, loading law only).
        kmin = -1
        kind = 0
        th_min = 2.0
        for k in range(n):
            g1 = _gap(u1, k, n)
            if (closed[k] > 0.0 and g1 < 0.0) or (closed[k] == 0.0 and g1 > 0.0):
                th = _first_violation(_gap(u, k, n), h * _gap(v, k, n), g1,
                                      h * _gap(v1, k, n), closed[k] > 0.0)
                if th < th_min:
                    th_min = th
                    kmin = k
                    kind = 0
            elif loading and closed[k] > 0.0:
                r1 = _gap(v1, k, n)
                if (damp[k] > 0.0 and r1 < -rate_tol) or (damp[k] == 0.0 and r1 > rate_tol):
                    th = _first_violation(_gap(v, k, n), h * _gap(a0, k, n), r1,
                                          h * _gap(a1, k, n), damp[k] > 0.0)
                    if th < th_min:
                        th_min = th
                        kmin = k
                        kind = 1
        if kmin >= 0:
            if th_min <= _THETA_NOW and toggles_here < 4 * n:
                # The contact changes state now: toggle and redo the step.
                toggles_here += 1
                if _toggle(kind, kmin, closed, damp):
                    grade = grade_levels + 1
                accelerations(u, v, A, gam, law, closed, damp, load, inv_m, F, a0)
                continue
            if th_min > _THETA_NOW:
                # Cut the step back to the crossing; refine by Newton on the event function.
                hc = th_min * h
                for it in range(_NEWTON_MAX + 1):
                    rk_step(u, v, a0, hc, A, gam, law, closed, damp, load, inv_m, ku, kv, tu,
                            F, u1, v1)
                    steps += 1
                    if it == _NEWTON_MAX or kind == 1:
                        # A rate switch is only a kink of the force: the cubic estimate of its
                        # time (error O(h^4)) is ample, no Newton refinement.
                        break
                    if kind == 0:
                        g = _gap(u1, kmin, n)
                        r = _gap(v1, kmin, n)
                    else:
                        accelerations(u1, v1, A, gam, law, closed, damp, load, inv_m, F, a1)
                        g = _gap(v1, kmin, n)
                        r = _gap(a1, kmin, n)
                    if abs(g) <= _GAP_TOL * h * abs(r) or r == 0.0:
                        break
                    hn = hc - g / r
                    if hn <= 0.0 or hn > h:
                        break
                    hc = hn
                # (u1, v1) is the state at t + hc.
                h = hc
        accelerations(u1, v1, A, gam, law, closed, damp, load, inv_m, F, a1)
        j = _sample(t_out, j, t, h, 1e-3 * dt, u, v, a0, u1, v1, a1, A, gam, law, closed, damp,
                    store_uv, out_F, out_d, out_u, out_v, us, vs, F)
        t += h
        u, u1 = u1, u
        v, v1 = v1, v
        toggles_here = 0
        if grade > 0:
            grade -= 1
        if kmin >= 0 and th_min > _THETA_NOW:
            if _toggle(kind, kmin, closed, damp):
                grade = grade_levels + 1
            accelerations(u, v, A, gam, law, closed, damp, load, inv_m, F, a0)
        else:
            a0, a1 = a1, a0
    return steps


@nb.njit(cache=True, parallel=True)
def integrate_batch(u_init, v_init, mass, A, gam, law, load, t_out, dt, grade_levels, rate_tol,
                    out_F, out_d):
    """Integrate ``runs`` chains in parallel; arrays carry a leading run axis.

    dt has shape (runs,). Returns the number of steps of each run.
    """
    runs = u_init.shape[0]
    n = u_init.shape[1]
    steps = np.zeros(runs, dtype=np.int64)
    dummy = np.empty((1, n))
    for r in nb.prange(runs):
        steps[r] = integrate(u_init[r], v_init[r], mass[r], A[r], gam[r], law, load[r],
                             t_out, dt[r], grade_levels, rate_tol[r], False, out_F[r], out_d[r],
                             dummy, dummy)
    return steps
