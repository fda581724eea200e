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
When only forces and approaches are wanted, the interpolant is applied directly to the gaps
and approach rates (it is linear in the end data), fused with the force law.

Performance layout (measured on the paper chain, n = 30: ~1.5 us per step including events,
~60 ns per output sample): the particle arrays are padded with zeros to a multiple of 8
entries past the wall, so the wall contact needs no special case and the force, stage and
sampling loops vectorise without scalar remainders; the contact states enter as the products
closed * A and dashpot * gamma, updated only when a contact toggles. A 6th-order 7-stage
Runge-Kutta formula (Butcher 1964) was tried in place of DOP853: it needs t_c/16 steps for
the 1e-6 peak-force target against t_c/8 here, so no net gain.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _dop

N_STAGES = _dop.N_STAGES
RK_A = np.ascontiguousarray(_dop.A[:N_STAGES, :N_STAGES], dtype=np.float64)
RK_B = np.ascontiguousarray(_dop.B, dtype=np.float64)
# Second-order form (u' = v): nodes c = A 1, and the coefficients of the stage and final
# displacements in the stage accelerations, A A and b A.
RK_C = RK_A.sum(axis=1)
RK_AA = RK_A @ RK_A
RK_BA = RK_B @ RK_A
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
# State arrays are padded to a multiple of this length (8 doubles = one AVX-512 register).
_PAD = 8


# Fused multiply-add, and no NaN/Inf/signed-zero special cases so that max() and sqrt
# vectorise; no reassociation (sums keep their order, results are reproducible).
_FM = {"contract", "nnan", "ninf", "nsz"}


@nb.njit(cache=True, fastmath=_FM)
def contact_forces(u, v, cA, cg, law, Fp):
    """Contact forces (N) on the padded layout, shifted by one into ``Fp``.

    Padded layout: ``p`` >= n is n rounded up to a multiple of ``_PAD`` and ``u``, ``v``
    have shape (p + 1,) with zeros from entry n on (entry n is the wall), so contact k is
    always between entries k and k + 1 and every loop runs over p entries, vectorised
    without a scalar remainder. ``cA`` = closed * A and ``cg`` = dashpot-on * gamma, shape
    (p,), zero past n, carry the contact states (so the loop has no branches). ``Fp``
    (p + 1,) receives ``Fp[0] = 0`` and ``Fp[k + 1]`` = force of contact k.
    """
    n = cA.shape[0]
    Fp[0] = 0.0
    if law == LAW_HKK:
        for k in range(n):
            dp = max(u[k] - u[k + 1], 0.0)
            Fp[k + 1] = np.sqrt(dp) * (cA[k] * dp + cg[k] * (v[k] - v[k + 1]))
    else:
        for k in range(n):
            dp = max(u[k] - u[k + 1], 0.0)
            Fp[k + 1] = cA[k] * dp * np.sqrt(dp) + cg[k] * (v[k] - v[k + 1])


@nb.njit(cache=True, fastmath=_FM)
def accelerations(u, v, cA, cg, law, load, inv_m, Fp, out):
    """Accelerations (m/s^2) into ``out`` (p + 1,) on the padded layout (zero past n).

    ``load`` and ``inv_m`` are padded with zeros to (p,).

    ``Fp`` receives the shifted contact forces (:func:`contact_forces`), which makes the
    particle balance one branch-free loop.
    """
    n = cA.shape[0]
    contact_forces(u, v, cA, cg, law, Fp)
    for i in range(n):
        out[i] = (load[i] + Fp[i] - Fp[i + 1]) * inv_m[i]
    for i in range(n, u.shape[0]):
        out[i] = 0.0


@nb.njit(cache=True, fastmath=_FM)
def rk_step(u, v, a0, h, cA, cg, law, load, inv_m, kv, tu, tv, Fp, u1, v1):
    """One DOP853 step of size ``h`` from (u, v) with a0 = acceleration at (u, v).

    Padded layout (see :func:`contact_forces`). ``kv[s]`` receives the stage accelerations;
    ``tu``, ``tv`` are scratch for the stage state. Since u' = v, the stage displacements
    are u + c_s h v + h^2 sum_l (A A)_sl kv_l and the stage velocities v + h sum_l A_sl kv_l
    (the same Runge-Kutta method as on the first-order system): one pass over the stage
    accelerations serves both sums and no stage velocities are stored.
    """
    m = cA.shape[0]  # p: entry p of every array stays 0
    hh = h * h
    for i in range(m):
        kv[0, i] = a0[i]
    for s in range(1, N_STAGES):
        ch = h * RK_C[s]
        for i in range(m):
            tu[i] = u[i] + ch * v[i]
            tv[i] = v[i]
        for j in range(s):
            cu = hh * RK_AA[s, j]
            cv = h * RK_A[s, j]
            if cu == 0.0 and cv == 0.0:
                continue
            for i in range(m):
                tu[i] += cu * kv[j, i]
                tv[i] += cv * kv[j, i]
        accelerations(tu, tv, cA, cg, law, load, inv_m, Fp, kv[s])
    for i in range(m):
        u1[i] = u[i] + h * v[i]
        v1[i] = v[i]
    for s in range(N_STAGES):
        bu = hh * RK_BA[s]
        bv = h * RK_B[s]
        for i in range(m):
            u1[i] += bu * kv[s, i]
            v1[i] += bv * kv[s, i]


@nb.njit(cache=True, inline="always")
def _gap(x, k):
    # Padded layout: x[n] is the wall, so the wall contact needs no special case.
    return x[k] - x[k + 1]


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


@nb.njit(cache=True, fastmath=_FM)
def _sample(t_out, j, t0, h, tiny, u0, v0, a0, u1, v1, a1, cA, cg, law, store_uv,
            out_F, out_d, out_u, out_v, us, vs, Fp, gs):
    """Write the quintic-Hermite samples with t0 < t_out[j] <= t0 + h; return the next j.

    Padded layout (see :func:`contact_forces`); ``us``, ``vs``, ``Fp`` (m,) and ``gs``
    (6, n) are scratch. Without ``store_uv`` the interpolant is evaluated directly on the
    contact gaps and rates (the Hermite form is linear in the end data), fused with the
    force law: one pass per sample, no particle arrays.
    """
    n = out_F.shape[1]
    m = cA.shape[0]
    nt = t_out.shape[0]
    hh = h * h
    inv_h = 1.0 / h
    if j >= nt or t_out[j] > t0 + h:
        return j
    gap_space = not store_uv and h >= tiny
    if gap_space:
        # Gap-space end data: gap, its change over the step, rates, relative accelerations.
        for k in range(n):
            gs[0, k] = u0[k] - u0[k + 1]
            gs[1, k] = (u1[k] - u1[k + 1]) - gs[0, k]
            gs[2, k] = v0[k] - v0[k + 1]
            gs[3, k] = a0[k] - a0[k + 1]
            gs[4, k] = v1[k] - v1[k + 1]
            gs[5, k] = a1[k] - a1[k + 1]
    hkk = law == LAW_HKK
    while j < nt and t_out[j] <= t0 + h:
        tau = t_out[j] - t0
        # Quintic Hermite basis on [0, 1] (h00 + h01 = 1) and its derivative (e00 = -e01),
        # with the step factors folded in once per sample rather than per particle.
        s = tau * inv_h
        s2 = s * s
        s3 = s2 * s
        s4 = s3 * s
        s5 = s4 * s
        h01 = 10 * s3 - 15 * s4 + 6 * s5
        c_v0 = h * (s - 6 * s3 + 8 * s4 - 3 * s5)
        c_a0 = hh * (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5)
        c_v1 = h * (-4 * s3 + 7 * s4 - 3 * s5)
        c_a1 = hh * (0.5 * s3 - s4 + 0.5 * s5)
        d_du = (30 * s2 - 60 * s3 + 30 * s4) * inv_h
        e10 = 1 - 18 * s2 + 32 * s3 - 15 * s4
        d_a0 = h * (s - 4.5 * s2 + 6 * s3 - 2.5 * s4)
        e11 = -12 * s2 + 28 * s3 - 15 * s4
        d_a1 = h * (1.5 * s2 - 4 * s3 + 2.5 * s4)
        if gap_space:
            # One fused pass per sample (the law test is hoisted out of the loop).
            if hkk:
                for k in range(n):
                    g = (gs[0, k] + h01 * gs[1, k] + c_v0 * gs[2, k] + c_a0 * gs[3, k]
                         + c_v1 * gs[4, k] + c_a1 * gs[5, k])
                    r = (d_du * gs[1, k] + e10 * gs[2, k] + d_a0 * gs[3, k] + e11 * gs[4, k]
                         + d_a1 * gs[5, k])
                    dp = max(g, 0.0)
                    out_d[j, k] = dp
                    out_F[j, k] = np.sqrt(dp) * (cA[k] * dp + cg[k] * r)
            else:
                for k in range(n):
                    g = (gs[0, k] + h01 * gs[1, k] + c_v0 * gs[2, k] + c_a0 * gs[3, k]
                         + c_v1 * gs[4, k] + c_a1 * gs[5, k])
                    r = (d_du * gs[1, k] + e10 * gs[2, k] + d_a0 * gs[3, k] + e11 * gs[4, k]
                         + d_a1 * gs[5, k])
                    dp = max(g, 0.0)
                    out_d[j, k] = dp
                    out_F[j, k] = cA[k] * dp * np.sqrt(dp) + cg[k] * r
            j += 1
            continue
        if h < tiny:
            # A sliver step (cut at a contact event): Taylor from the left end, error O(h^3);
            # the Hermite form would divide rounding noise of u1 - u0 by h.
            for i in range(m):
                us[i] = u0[i] + tau * (v0[i] + 0.5 * tau * a0[i])
                vs[i] = v0[i] + tau * a0[i]
        else:
            for i in range(m):
                # Written with u1 - u0 to limit cancellation.
                du = u1[i] - u0[i]
                us[i] = (u0[i] + h01 * du + c_v0 * v0[i] + c_a0 * a0[i]
                         + c_v1 * v1[i] + c_a1 * a1[i])
                vs[i] = d_du * du + e10 * v0[i] + d_a0 * a0[i] + e11 * v1[i] + d_a1 * a1[i]
        contact_forces(us, vs, cA, cg, law, Fp)
        for k in range(n):
            out_F[j, k] = Fp[k + 1]
            out_d[j, k] = max(us[k] - us[k + 1], 0.0)
        if store_uv:
            for k in range(n):
                out_u[j, k] = us[k]
                out_v[j, k] = vs[k]
        j += 1
    return j


@nb.njit(cache=True)
def _toggle(kind, k, closed, damp, A, gam, cA, cg):
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
    p = -(-n // _PAD) * _PAD  # padded layout (see contact_forces): entries n.. stay 0
    m = p + 1
    inv_m = np.zeros(p)
    inv_m[:n] = 1.0 / mass
    load_p = np.zeros(p)
    load_p[:n] = load
    u = np.zeros(m)
    v = np.zeros(m)
    u[:n] = u_init
    v[:n] = v_init
    u1 = np.zeros(m)
    v1 = np.zeros(m)
    a0 = np.zeros(m)
    a1 = np.zeros(m)
    kv = np.zeros((N_STAGES, m))
    tu = np.zeros(m)
    tv = np.zeros(m)
    F = np.zeros(m)
    us = np.zeros(m)
    gs = np.zeros((6, n))
    vs = np.zeros(m)
    closed = np.zeros(n)
    damp = np.zeros(n)
    cA = np.zeros(p)
    cg = np.zeros(p)
    loading = law == LAW_LINEAR_LOADING
    for k in range(n):
        g = _gap(u, k)
        r = _gap(v, k)
        closed[k] = 1.0 if (g > 0.0 or (g == 0.0 and r > 0.0)) else 0.0
        damp[k] = closed[k] * (1.0 if (not loading or r > 0.0) else 0.0)
        cA[k] = closed[k] * A[k]
        cg[k] = damp[k] * gam[k]
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    accelerations(u, v, cA, cg, law, load_p, inv_m, F, a0)
    j = 0
    # Samples at the initial time.
    while j < nt and t_out[j] <= 0.0:
        j = _sample(t_out, j, -1.0, 1.0, 0.0, u, v, a0, u, v, a0, cA, cg, law,
                    store_uv, out_F, out_d, out_u, out_v, us, vs, F, gs)
    t = 0.0
    steps = 0
    toggles_here = 0
    h_floor = dt / 2.0**grade_levels
    # Steps left in a geometric grading after a contact closed (sizes dt 2^-min(grade, K)).
    grade = 0
    for k in range(n):
        if closed[k] > 0.0 and _gap(u, k) == 0.0:
            grade = grade_levels + 1
    while j < nt:
        h = dt
        if grade > 0:
            h = dt / 2.0 ** min(grade, grade_levels)
        else:
            # Approach a closed contact that is about to open in halving steps.
            for k in range(n):
                if closed[k] > 0.0:
                    r = _gap(v, k)
                    if r < 0.0:
                        tau = -_gap(u, k) / r
                        if 2.0 * h_floor < tau < 2.0 * h:
                            h = 0.5 * tau
        if t + h > t_end - 0.01 * dt:
            # Stretch the last step by at most 1% rather than leave a sliver.
            h = t_end - t
        if h <= 0.0:
            h = dt  # only rounding left: finish the last samples with one more step
        rk_step(u, v, a0, h, cA, cg, law, load_p, inv_m, kv, tu, tv, F, u1, v1)
        steps += 1
        if loading:
            accelerations(u1, v1, cA, cg, law, load_p, inv_m, F, a1)
        # Find the earliest violated contact state: kind 0 = gap (open/closed), kind 1 = the
        # sign of the approach rate (dashpot on/off, loading law only).
        kmin = -1
        kind = 0
        th_min = 2.0
        for k in range(n):
            g1 = _gap(u1, k)
            if (closed[k] > 0.0 and g1 < 0.0) or (closed[k] == 0.0 and g1 > 0.0):
                th = _first_violation(_gap(u, k), h * _gap(v, k), g1,
                                      h * _gap(v1, k), closed[k] > 0.0)
                if th < th_min:
                    th_min = th
                    kmin = k
                    kind = 0
            elif loading and closed[k] > 0.0:
                r1 = _gap(v1, k)
                if (damp[k] > 0.0 and r1 < -rate_tol) or (damp[k] == 0.0 and r1 > rate_tol):
                    th = _first_violation(_gap(v, k), h * _gap(a0, k), r1,
                                          h * _gap(a1, k), damp[k] > 0.0)
                    if th < th_min:
                        th_min = th
                        kmin = k
                        kind = 1
        if kmin >= 0:
            if th_min <= _THETA_NOW and toggles_here < 4 * n:
                # The contact changes state now: toggle and redo the step.
                toggles_here += 1
                if _toggle(kind, kmin, closed, damp, A, gam, cA, cg):
                    grade = grade_levels + 1
                accelerations(u, v, cA, cg, law, load_p, inv_m, F, a0)
                continue
            if th_min > _THETA_NOW:
                # Cut the step back to the crossing; refine by Newton on the event function.
                hc = th_min * h
                for it in range(_NEWTON_MAX + 1):
                    rk_step(u, v, a0, hc, cA, cg, law, load_p, inv_m, kv, tu, tv, F, u1, v1)
                    steps += 1
                    if it == _NEWTON_MAX or kind == 1:
                        # A rate switch is only a kink of the force: the cubic estimate of its
                        # time (error O(h^4)) is ample, no Newton refinement.
                        break
                    if kind == 0:
                        g = _gap(u1, kmin)
                        r = _gap(v1, kmin)
                    else:
                        accelerations(u1, v1, cA, cg, law, load_p, inv_m, F, a1)
                        g = _gap(v1, kmin)
                        r = _gap(a1, kmin)
                    if abs(g) <= _GAP_TOL * h * abs(r) or r == 0.0:
                        break
                    hn = hc - g / r
                    if hn <= 0.0 or hn > h:
                        break
                    hc = hn
                # (u1, v1) is the state at t + hc.
                h = hc
        accelerations(u1, v1, cA, cg, law, load_p, inv_m, F, a1)
        j = _sample(t_out, j, t, h, 1e-3 * dt, u, v, a0, u1, v1, a1, cA, cg, law,
                    store_uv, out_F, out_d, out_u, out_v, us, vs, F, gs)
        t += h
        u, u1 = u1, u
        v, v1 = v1, v
        toggles_here = 0
        if grade > 0:
            grade -= 1
        if kmin >= 0 and th_min > _THETA_NOW:
            if _toggle(kind, kmin, closed, damp, A, gam, cA, cg):
                grade = grade_levels + 1
            accelerations(u, v, cA, cg, law, load_p, inv_m, F, a0)
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
