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
re-run the RK step to the new end until the residual gap is below ``1e-7 h |d(gap)/dt|``
where the force jumps at the switch (a dashpot acting), ``1e-4 h |d(gap)/dt|`` where it is
continuous (an error e in the time then moves the impulse by ~ A rate^{3/2} e^{5/2}); the
contact is toggled there and the step sequence resumes with the nominal step. If another
contact is found in a violated state at the end of the cut step (it switched and switched
back within the uncut step, invisible at its end), the step is redone to there so that the
earlier switch is found. A state that switched at a step's start within the tolerance of
its time is not a violation while it leaves the wrong sign (no chatter).

Even with exact switch times, F ~ (t - t_0)^{3/2} near a switch is not smooth: the solution
has a (t - t_0)^{7/2} term ((t - t_0)^{5/2} for Kuwabara-Kono) that caps the order of a step
starting or ending at t_0. The steps next to a switch are therefore taken in s = sqrt(|t -
t_0|), in which the solution's expansion (powers of (t - t_0)^{1/2}) is smooth
(:mod:`msens.chain.dop853_codegen`): the step after a closing in s = sqrt(t - t_0)
(``STEP_SQRT_START``, length dt 2^-K, then steps dt 2^-(K-1), ..., dt/2, each at most twice
the time since the closing; K = ``grade_levels``, deeper for a grazing closing whose rate
changes within the first step),
and the step to an opening in s = sqrt(t_0 - t) (``STEP_SQRT_END``). An opening is foreseen
from the gap's Taylor polynomial to second order; the contact is approached in halving steps
to within dt/4 and the last step, in s, ends at the estimate, its length refined by Newton
until the gap at its end is below the tolerance above. (Before, the steps were graded
geometrically down to dt/16 on both sides of every switch: on the paper chain 482 steps per
ms against 403 now, 1495 against 1011 without damping, where contacts open and close ~170
times per ms; 907 with the relaxed tolerance above.) Dense output inside such a step is a
polynomial in s (:func:`_sample_sqrt`).

With the loading-only dashpot (``LAW_LINEAR_LOADING``) the dashpot of a closed contact is a
second state, switched where the approach rate changes sign (a kink of the force), located
on the cubic Hermite interpolant of the rate (values and relative accelerations) without
Newton refinement: an O(h^4) error in the time of a kink is harmless. Rates below
``rate_tol`` do not switch it, so the resting part of the chain does not chatter. Most of
these switches are *predicted* instead: the quintic Hermite polynomial through the rate and
its first two derivatives at this and the previous step's start, extrapolated, gives the
rate's next zero, and the step is shortened (or stretched by at most 1 %) to end there; the
switch is taken at the step's end when the zero lies within 1e-3 steps of it, else the step
is cut back as above. Where a contact nearby switched at this step's start, the derivatives'
left limits there enter the fit and their jumps are added to the extrapolation. On the paper
chain (at the former default step t_c/8) a cubic predictor from the rate and its first
derivative removed ~3/4 of the cut-back steps (1318 -> 984 steps per ms) at an unchanged
peak-force error. Contacts without a dashpot (gamma = 0, e.g. the paper's wall) track no
dashpot switches (-> 978 steps; 837 at t_c/5; 733 with the steps in s; 652 with the quintic
predictor, which also needs the jerks at every step, and the relaxed tolerance above).

The Runge-Kutta method is the 12-stage 8th-order formula of Dormand & Prince (DOP853,
Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., Springer 1993, §II.5), run at a fixed
step. Its step is generated code (:mod:`msens.chain._dop853_step`, written by
:mod:`msens.chain.dop853_codegen` from SciPy's coefficients,
``scipy.integrate._ivp.dop853_coefficients``) so that the coefficients are neither retyped
nor looped over.

All functions are compiled with ``cache=True`` (first call ~5 s, then loaded from the cache).

Dense output (arbitrary output times) is the septic Hermite interpolant through the
displacement, velocity, acceleration and jerk at the two ends of the step that contains the
time (error O(h^8) in u, O(h^7) in v); the jerk follows from differentiating Eq. 6 along the
motion (:func:`jerks`) and is only formed for steps that hold output samples. The contact
forces are evaluated from the interpolated state with the step's contact states. When only
forces and approaches are wanted, the interpolant is applied directly to the gaps and
approach rates (it is linear in the end data), fused with the force law. The
Kuwabara-Kono force has an unbounded jerk where a contact opens or closes; that law keeps the
quintic interpolant through (u, v, a) (O(h^6), O(h^5)).

Why septic: with the quintic the interpolant, not the integration, set the error. On the
paper chain at t_c/8 the forces at the step ends erred by <= 1e-8 of the peak force but the
samples in between by 4.5e-7 (linear dashpot). The jerk costs one force-like pass per sampled
step; in exchange the step grows to t_c/5 at a peak-force error of 4e-8 (482 instead of 673
steps per ms).

Performance layout (``benchmarks/chain_speed.py``, paper chain, n = 30: 0.64-0.67 ms for 403
steps and 10,001 output samples with the linear dashpot, 1.00-1.07 ms for 651 with the
loading-only one): the particle arrays and output rows are padded with zeros to a multiple of 8
entries past the wall, so the wall contact needs no special case and the force, stage and
sampling loops vectorise without scalar remainders; the contact states enter as the products
closed * A and dashpot * gamma, updated only when a contact toggles. The states themselves are
padded the same way, so that the per-step event passes (violated states, contacts that may open
within the step, dashpot-switch candidates) are branch-free counts over p entries that
vectorise; the scalar work (the least opening time, the switch predictor) then visits only the
flagged contacts. (Over n = 30 entries LLVM's vector loop, 8 lanes x 4, never ran: all of it
was the scalar remainder. With the candidates' tests as branches the predictor's scan took a
sixth of the run time. ``benchmarks/chain_profile.py``, two runs each, before (``git checkout
8cea9a2 -- src/msens/chain/kernel.py``) and after: 1100-1123 against 925-938 us per run at the
same steps; ns per step for the openings 127-131 -> 54-55, the predictor 257-258 -> 187-192,
the violated-state test 143-154 -> 94.) The Runge-Kutta step and the other passes over the
particle arrays are compiled with their array arguments declared free of overlap
(:func:`msens.chain._noalias.njit_noalias`): without, every vectorised loop began with run-time
overlap checks of each pair of arrays, which cost more than the loop (the DOP853 step 954 ->
465-511 ns, see :mod:`msens.chain._noalias`). The scratch arrays start on 64-byte boundaries
(:func:`_zeros64`). Helpers called inside the sampling loops take scalars, not arrays: numba's
reference counting of array arguments of inlined helpers stopped those loops from vectorising
(sampling 1.5x slower). A 6th-order 7-stage Runge-Kutta formula (Butcher 1964) was tried in
place of DOP853: it needs t_c/16 steps for the 1e-6 peak-force target against t_c/8 for DOP853
(quintic output), so no net gain.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain._dop853_step import (
    FASTMATH,
    N_STAGES,
    STEP_REGULAR,
    STEP_SQRT_END,
    STEP_SQRT_START,
    rk_step,
)
from msens.chain._noalias import njit_noalias

#: Order of the Runge-Kutta formula.
RK_ORDER = 8

LAW_LINEAR = 0
LAW_HKK = 1
LAW_LINEAR_LOADING = 2

# A contact whose crossing falls within this fraction of a step from its start toggles at once.
_THETA_NOW = 1e-9
# Newton refinement of a crossing stops when |gap| < _GAP_TOL * h * |d(gap)/dt|, i.e. the
# switch time errs by less than _GAP_TOL steps, where the force jumps there (by gamma * rate:
# a dashpot acting at the switch). Where it is continuous (Kuwabara-Kono, no dashpot, or
# the loading-only dashpot at an opening) _GAP_TOL_SMOOTH: an error e in the time changes the
# impulse by ~ A rate^1.5 e^2.5 and the force near the switch by ~ A (rate e)^1.5, < 1e-7 of
# the peak on the paper chain.
_GAP_TOL = 1e-7
_GAP_TOL_SMOOTH = 1e-4
_NEWTON_MAX = 4
# A predicted dashpot switch is accepted at the end of a step when the rate's zero lies
# within this fraction of the step from it.
_PRED_TOL = 1e-3
# A state that switched at a step's start may have the wrong sign there by the tolerance of
# its time (_GAP_TOL_SMOOTH, _PRED_TOL steps): not a violation if it leaves the wrong sign
# within this many steps.
_SWITCH_SLACK = 2e-3
# A closing is grazing when its rate changes by itself (2 |rate| / |relative acceleration|)
# within 1 / _CLOSE_FRAC first steps; its grading then deepens, to at most _CLOSE_MAX levels.
_CLOSE_FRAC = 0.5
_CLOSE_MAX = 8
# Longest step taken in sqrt(t0 - t) to an opening, in nominal steps (1/2 errs 1e-6 on the
# rebound speed of a single Hertz collision at t_c/5, 1/4 6e-9).
_END_FRAC = 0.25
# Steps with at most this many output samples evaluate the interpolant from its weights;
# more amortise forming its monomial coefficients.
_FEW_SAMPLES = 3
# A step may be stretched by this fraction to end at a predicted dashpot switch.
_PRED_STRETCH = 1e-2
# State arrays are padded to a multiple of this length (8 doubles = one AVX-512 register).
_PAD = 8


_FM = set(FASTMATH)


@nb.njit(cache=True)
def padded_length(n: int) -> int:
    """Row length p of the output arrays for n particles: n rounded up to a multiple of 8."""
    return -(-n // _PAD) * _PAD


@nb.njit(cache=True)
def _zeros64(size):
    """Zeros of shape (size,) starting on a 64-byte boundary (a cache line, one AVX-512
    register). numba aligns arrays to 32 bytes only, so whether the scratch arrays' full-width
    loads straddle cache lines varied with the heap's state (the start offset changed run
    times by up to 4 % in a test of four offsets); aligned, the layout is the same in every
    run."""
    buf = np.zeros(size + 8)
    off = (-(buf.ctypes.data // 8)) % 8
    return buf[off:off + size]


@nb.njit(cache=True)
def _zeros64_rows(rows, cols):
    """Zeros of shape (rows, c), c = cols rounded up to a multiple of 8, so that every row
    starts on a 64-byte boundary (C-contiguous; the columns past cols are spare)."""
    stride = padded_length(cols)
    return _zeros64(rows * stride).reshape((rows, stride))


@nb.njit(cache=True, inline="always")
def _force(g, r, cA, cg, hkk):
    # Force of a contact (coefficients cA = closed * A, cg = dashpot * gamma) from its gap g
    # and gap rate r, written as in the generated Runge-Kutta step. (The loop-invariant law
    # test is hoisted: loop unswitching.)
    dp = max(g, 0.0)
    w = np.sqrt(dp)
    return cA * dp * w + cg * r * (w if hkk else 1.0)


@njit_noalias(cache=True, fastmath=_FM)
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
    hkk = law == LAW_HKK
    Fp[0] = 0.0
    for k in range(n):
        Fp[k + 1] = _force(u[k] - u[k + 1], v[k] - v[k + 1], cA[k], cg[k], hkk)


@njit_noalias(cache=True, fastmath=_FM)
def accelerations(u, v, cA, cg, law, load, inv_m, out):
    """Accelerations (m/s^2) into ``out`` (p + 1,) on the padded layout (zero past n).

    ``load`` and ``inv_m`` are padded with zeros to (p,). Forces and the particle balance
    in one branch-free pass, as in the generated Runge-Kutta step: the force of the contact
    above particle k is carried over from the previous iteration.
    """
    n = cA.shape[0]
    hkk = law == LAW_HKK
    f_prev = 0.0
    for k in range(n):
        f = _force(u[k] - u[k + 1], v[k] - v[k + 1], cA[k], cg[k], hkk)
        out[k] = (load[k] + f_prev - f) * inv_m[k]
        f_prev = f
    for i in range(n, u.shape[0]):
        out[i] = 0.0


@nb.njit(cache=True, inline="always")
def _dforce(g, r, q, cA, cg):
    # dF/dt of a contact along the motion (linear-dashpot laws) from its gap g, gap rate r and
    # relative acceleration q (scalars, so that the calling loops vectorise).
    return 1.5 * cA * np.sqrt(max(g, 0.0)) * r + cg * q


@njit_noalias(cache=True, fastmath=_FM)
def jerks(u, v, a, cA, cg, inv_m, out):
    """Time derivatives of the accelerations (m/s^3) into ``out`` (p + 1,), linear-dashpot laws.

    Differentiates Eq. 6 along the motion: dF/dt = (3/2) A sqrt(delta) d(delta)/dt
    + gamma d^2(delta)/dt^2 with the relative acceleration from ``a``. Padded layout as in
    :func:`accelerations` (one pass). (Not for the Kuwabara-Kono law, whose dF/dt is
    unbounded where a contact opens or closes.)
    """
    n = cA.shape[0]
    d_prev = 0.0
    for k in range(n):
        d = _dforce(u[k] - u[k + 1], v[k] - v[k + 1], a[k] - a[k + 1], cA[k], cg[k])
        out[k] = (d_prev - d) * inv_m[k]
        d_prev = d
    for i in range(n, u.shape[0]):
        out[i] = 0.0


@nb.njit(cache=True, inline="always")
def _hermite_coefficients(septic, p0, d0, e0, f0, dp, d1, e1, f1):
    """Monomial coefficients c1..c7 in s of the Hermite interpolant on s in [0, 1].

    End data: values p0 and p0 + dp, first, second and third derivatives in s (d, e, f =
    the time derivatives times h, h^2, h^3). Septic (error O(h^8)) with the third
    derivatives, else quintic (O(h^6); f ignored, c6 = c7 = 0). c0 = p0.
    """
    if septic:
        c4 = (35.0 * dp - 20.0 * d0 - 15.0 * d1 - 5.0 * e0 + 2.5 * e1
              - (2.0 / 3.0) * f0 - f1 / 6.0)
        c5 = -84.0 * dp + 45.0 * d0 + 39.0 * d1 + 10.0 * e0 - 7.0 * e1 + f0 + 0.5 * f1
        c6 = (70.0 * dp - 36.0 * d0 - 34.0 * d1 - 7.5 * e0 + 6.5 * e1
              - (2.0 / 3.0) * f0 - 0.5 * f1)
        c7 = -20.0 * dp + 10.0 * d0 + 10.0 * d1 + 2.0 * e0 - 2.0 * e1 + (f0 + f1) / 6.0
        return d0, 0.5 * e0, f0 / 6.0, c4, c5, c6, c7
    c3 = 10.0 * dp - 6.0 * d0 - 1.5 * e0 - 4.0 * d1 + 0.5 * e1
    c4 = -15.0 * dp + 8.0 * d0 + 1.5 * e0 + 7.0 * d1 - e1
    c5 = 6.0 * dp - 3.0 * d0 - 0.5 * e0 - 3.0 * d1 + 0.5 * e1
    return d0, 0.5 * e0, c3, c4, c5, 0.0, 0.0


@nb.njit(cache=True, inline="always")
def _hermite_weights(septic, x, h):
    """Weights of the end data in the Hermite interpolant at s = x of a step of size h.

    Returns (w_dp, w_r0, w_r1, w_q0, w_q1, w_s0, w_s1) for the value, where value = p0
    + w_dp dp + w_r0 r0 + ... (dp = increment, r rates, q accelerations, s jerks at the two
    ends), then the same seven weights for its time derivative (rate = v_dp dp + v_r0 r0
    + ...). Septic or quintic as in :func:`_hermite_coefficients` (jerk weights 0).
    """
    x2 = x * x
    x3 = x2 * x
    x4 = x3 * x
    hh = h * h
    inv_h = 1.0 / h
    if septic:
        return (x4 * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x))),
                h * x * (1.0 + x3 * (-20.0 + x * (45.0 + x * (-36.0 + 10.0 * x)))),
                h * x4 * (-15.0 + x * (39.0 + x * (-34.0 + 10.0 * x))),
                hh * x2 * (0.5 + x2 * (-5.0 + x * (10.0 + x * (-7.5 + 2.0 * x)))),
                hh * x4 * (2.5 + x * (-7.0 + x * (6.5 - 2.0 * x))),
                hh * h * x3 * (1.0 / 6.0 + x * (-2.0 / 3.0 + x * (1.0 + x * (-2.0 / 3.0
                                                                    + x / 6.0)))),
                hh * h * x4 * (-1.0 / 6.0 + x * (0.5 + x * (-0.5 + x / 6.0))),
                inv_h * x3 * (140.0 + x * (-420.0 + x * (420.0 - 140.0 * x))),
                1.0 + x3 * (-80.0 + x * (225.0 + x * (-216.0 + 70.0 * x))),
                x3 * (-60.0 + x * (195.0 + x * (-204.0 + 70.0 * x))),
                h * x * (1.0 + x2 * (-20.0 + x * (50.0 + x * (-45.0 + 14.0 * x)))),
                h * x3 * (10.0 + x * (-35.0 + x * (39.0 - 14.0 * x))),
                hh * x2 * (0.5 + x * (-8.0 / 3.0 + x * (5.0 + x * (-4.0 + 7.0 * x / 6.0)))),
                hh * x3 * (-2.0 / 3.0 + x * (2.5 + x * (-3.0 + 7.0 * x / 6.0))))
    return (x3 * (10.0 + x * (-15.0 + 6.0 * x)),
            h * x * (1.0 + x2 * (-6.0 + x * (8.0 - 3.0 * x))),
            h * x3 * (-4.0 + x * (7.0 - 3.0 * x)),
            hh * x2 * (0.5 + x * (-1.5 + x * (1.5 - 0.5 * x))),
            hh * x3 * (0.5 + x * (-1.0 + 0.5 * x)),
            0.0, 0.0,
            inv_h * x2 * (30.0 + x * (-60.0 + 30.0 * x)),
            1.0 + x2 * (-18.0 + x * (32.0 - 15.0 * x)),
            x2 * (-12.0 + x * (28.0 - 15.0 * x)),
            h * x * (1.0 + x * (-4.5 + x * (6.0 - 2.5 * x))),
            h * x2 * (1.5 + x * (-4.0 + 2.5 * x)),
            0.0, 0.0)


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
        if p0 > -_SWITCH_SLACK * d0:
            return 0.0
        # Moving into the allowed sign within _SWITCH_SLACK steps: the state switched here,
        # within the tolerance of its time. (Toggling it back would chatter.)
        p0 = 0.0
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
    # Newton on the cubic inside the bracket, falling back to bisection when a Newton step
    # leaves it; the bracket keeps p(lo) <= 0 < p(hi), and hi is returned.
    th = 0.5 * (lo + hi)
    for _ in range(60):
        if hi - lo < 1e-13:
            break
        p = _hermite3(p0, d0, p1, d1, th)
        if p > 0.0:
            hi = th
        else:
            lo = th
        dp = _hermite3_slope(p0, d0, p1, d1, th)
        step = p / dp if dp != 0.0 else 0.0
        nxt = th - step
        if abs(step) < 1e-14 and p > 0.0:
            break
        th = nxt if lo < nxt < hi else 0.5 * (lo + hi)
    return hi


@nb.njit(cache=True)
def _rate_zero(r, q, s, ql, sl, rp, qp, sp, hp, tau_max):
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
def _hermite3_slope(p0, d0, p1, d1, t):
    # d/dt of _hermite3
    t2 = t * t
    return ((6.0 * t2 - 6.0 * t) * (p0 - p1) + (3.0 * t2 - 4.0 * t + 1.0) * d0
            + (3.0 * t2 - 2.0 * t) * d1)


@nb.njit(cache=True, inline="always")
def _hermite3(p0, d0, p1, d1, t):
    t2 = t * t
    t3 = t2 * t
    return ((2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * d0
            + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * d1)


@nb.njit(cache=True, inline="always")
def _sample(t_out, j, t0, h, tiny, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
            store_uv, out_F, out_d, out_u, out_v, us, vs, Fp, cs, sel, subset):
    """Write the dense-output samples with t0 < t_out[j] <= t0 + h; return the next j.

    The interpolant is the Hermite polynomial through the states, accelerations and (with
    ``septic``) jerks ``j0``/``j1`` at both ends of the step: septic, error O(h^8) in the
    gaps, O(h^7) in their rates; else quintic (O(h^6), O(h^5)). Padded layout (see
    :func:`contact_forces`): column c of ``out_F`` and ``out_d`` is contact ``sel[c]``, all
    contacts in order (``sel`` = 0, ..., p - 1, entries past n come out 0) unless
    ``subset``. ``us``, ``vs``, ``Fp`` (p + 1,) and ``cs`` (>= 8, p + 1) are scratch. Without
    ``store_uv`` the interpolant is applied directly to the contact gaps (it is linear in the
    end data), fused with the force law (:func:`_sample_gaps`); with ``store_uv``, or in a
    sliver step shorter than ``tiny``, per particle (:func:`_sample_states`).
    """
    if j >= t_out.shape[0] or t_out[j] > t0 + h:
        return j
    if store_uv or h < tiny:
        return _sample_states(t_out, j, t0, h, tiny, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg,
                              law, septic, store_uv, out_F, out_d, out_u, out_v, us, vs, Fp,
                              sel)
    if subset:
        return _sample_contacts(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law,
                                septic, out_F, out_d, cs, sel)
    return _sample_gaps(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                        out_F, out_d, cs)


@nb.njit(cache=True, fastmath=_FM)
def _sample_states(t_out, j, t0, h, tiny, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                   store_uv, out_F, out_d, out_u, out_v, us, vs, Fp, sel):
    """:func:`_sample` per particle: the states at each sample, then their forces."""
    m = cA.shape[0]
    nt = t_out.shape[0]
    if h < tiny:
        # A sliver step (cut at a contact event): Taylor from the left end, error O(h^3);
        # the Hermite form would divide rounding noise of u1 - u0 by h.
        while j < nt and t_out[j] <= t0 + h:
            tau = t_out[j] - t0
            for i in range(m + 1):
                us[i] = u0[i] + tau * (v0[i] + 0.5 * tau * a0[i])
                vs[i] = v0[i] + tau * a0[i]
            j = _store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel)
        return j
    inv_h = 1.0 / h
    while j < nt and t_out[j] <= t0 + h:
        (w_dp, w_r0, w_r1, w_q0, w_q1, w_s0, w_s1,
         v_dp, v_r0, v_r1, v_q0, v_q1, v_s0, v_s1) = _hermite_weights(
            septic, (t_out[j] - t0) * inv_h, h)
        for i in range(m + 1):
            du = u1[i] - u0[i]
            us[i] = (u0[i] + w_dp * du + w_r0 * v0[i] + w_r1 * v1[i] + w_q0 * a0[i]
                     + w_q1 * a1[i] + w_s0 * j0[i] + w_s1 * j1[i])
            vs[i] = (v_dp * du + v_r0 * v0[i] + v_r1 * v1[i] + v_q0 * a0[i]
                     + v_q1 * a1[i] + v_s0 * j0[i] + v_s1 * j1[i])
        j = _store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel)
    return j


@nb.njit(cache=True, inline="always")
def _gap_sample(k, w, u0, v0, a0, j0, u1, v1, a1, j1):
    """Gap and gap rate of contact k at a sample, from the weights ``w`` of
    :func:`_hermite_weights` (the interpolant is linear in the end data)."""
    (w_dp, w_r0, w_r1, w_q0, w_q1, w_s0, w_s1, v_dp, v_r0, v_r1, v_q0, v_q1, v_s0, v_s1) = w
    g0 = u0[k] - u0[k + 1]
    dg = (u1[k] - u1[k + 1]) - g0
    r0 = v0[k] - v0[k + 1]
    r1 = v1[k] - v1[k + 1]
    q0 = a0[k] - a0[k + 1]
    q1 = a1[k] - a1[k + 1]
    s0 = j0[k] - j0[k + 1]
    s1 = j1[k] - j1[k + 1]
    g = g0 + w_dp * dg + w_r0 * r0 + w_r1 * r1 + w_q0 * q0 + w_q1 * q1 + w_s0 * s0 + w_s1 * s1
    r = v_dp * dg + v_r0 * r0 + v_r1 * r1 + v_q0 * q0 + v_q1 * q1 + v_s0 * s0 + v_s1 * s1
    return g, r


@nb.njit(cache=True, inline="always")
def _gap_coefficients(cs, c, k, septic, h, hh, u0, v0, a0, j0, u1, v1, a1, j1):
    """Monomial coefficients in s of contact k's gap over the step (end data as in
    :func:`_sample`) into column c of ``cs`` (rows 0-7)."""
    g0 = u0[k] - u0[k + 1]
    c1, c2, c3, c4, c5, c6, c7 = _hermite_coefficients(
        septic, g0, h * (v0[k] - v0[k + 1]), hh * (a0[k] - a0[k + 1]),
        hh * h * (j0[k] - j0[k + 1]), (u1[k] - u1[k + 1]) - g0, h * (v1[k] - v1[k + 1]),
        hh * (a1[k] - a1[k + 1]), hh * h * (j1[k] - j1[k + 1]))
    cs[0, c] = g0
    cs[1, c] = c1
    cs[2, c] = c2
    cs[3, c] = c3
    cs[4, c] = c4
    cs[5, c] = c5
    cs[6, c] = c6
    cs[7, c] = c7


@nb.njit(cache=True, inline="always")
def _horner(cs, c, x):
    """Value and s-derivative at s = x of the polynomial in column c of ``cs`` (rows 0-7:
    coefficients of s^0..s^7)."""
    # Horner's scheme for both at once: the eight coefficients are loaded once (loads, not
    # arithmetic, bound the sampling loop: 25 % faster than separate sums for the gap and its
    # rate).
    g = cs[7, c]
    d = 0.0
    for q in range(6, -1, -1):
        d = d * x + g
        g = g * x + cs[q, c]
    return g, d


@nb.njit(cache=True, inline="always")
def _samples_in(t_out, j, t_end):
    # Number of output times from t_out[j] on that are <= t_end (sorted t_out).
    ns = 0
    while j + ns < t_out.shape[0] and t_out[j + ns] <= t_end:
        ns += 1
    return ns


@njit_noalias(cache=True, fastmath=_FM)
def _sample_gaps(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic, out_F,
                 out_d, cs):
    """:func:`_sample` on the contact gaps: in steps with more than ``_FEW_SAMPLES`` samples
    through the interpolant's eight monomial coefficients in s = tau / h (formed once per
    step into ``cs``; the rate is the derivative), else through the weights of the end data
    at each sample."""
    m = cA.shape[0]
    hkk = law == LAW_HKK
    inv_h = 1.0 / h
    ns = _samples_in(t_out, j, t0 + h)
    if ns <= _FEW_SAMPLES:
        for _ in range(ns):
            w = _hermite_weights(septic, (t_out[j] - t0) * inv_h, h)
            for k in range(m):
                g, r = _gap_sample(k, w, u0, v0, a0, j0, u1, v1, a1, j1)
                out_d[j, k] = g
                out_F[j, k] = _force(g, r, cA[k], cg[k], hkk)
            j += 1
        return j
    for k in range(m):
        _gap_coefficients(cs, k, k, septic, h, h * h, u0, v0, a0, j0, u1, v1, a1, j1)
    for _ in range(ns):
        x = (t_out[j] - t0) * inv_h
        for k in range(m):
            g, d = _horner(cs, k, x)
            out_d[j, k] = g
            out_F[j, k] = _force(g, d * inv_h, cA[k], cg[k], hkk)
        j += 1
    return j


@njit_noalias(cache=True, fastmath=_FM)
def _sample_contacts(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                     out_F, out_d, cs, sel):
    """:func:`_sample_gaps` for the contacts ``sel`` only (column c = contact sel[c]), with
    the same arithmetic per contact (so the same values)."""
    hkk = law == LAW_HKK
    inv_h = 1.0 / h
    ns = _samples_in(t_out, j, t0 + h)
    cols = sel.shape[0]
    if ns <= _FEW_SAMPLES:
        for _ in range(ns):
            w = _hermite_weights(septic, (t_out[j] - t0) * inv_h, h)
            for c in range(cols):
                k = sel[c]
                g, r = _gap_sample(k, w, u0, v0, a0, j0, u1, v1, a1, j1)
                out_d[j, c] = g
                out_F[j, c] = _force(g, r, cA[k], cg[k], hkk)
            j += 1
        return j
    for c in range(cols):
        _gap_coefficients(cs, c, sel[c], septic, h, h * h, u0, v0, a0, j0, u1, v1, a1, j1)
    for _ in range(ns):
        x = (t_out[j] - t0) * inv_h
        for c in range(cols):
            k = sel[c]
            g, d = _horner(cs, c, x)
            out_d[j, c] = g
            out_F[j, c] = _force(g, d * inv_h, cA[k], cg[k], hkk)
        j += 1
    return j


@nb.njit(cache=True, inline="always")
def _sqrt_coefficients(septic, hs, p0, r0, q0, s0, dp, r1, q1, s1):
    """Monomial coefficients c0..c10 of the interpolant of a step taken in x = sqrt((t -
    t_ref) / hs), t_ref its singular end (x = 0), hs = +-h.

    In x the solution is P(t_ref + hs x^2) + (singular terms): the even coefficients are the
    Taylor coefficients of the regular part P at t_ref (value p0, rate r0, acceleration q0,
    jerk s0: c2 = hs r0, c4 = hs^2 q0 / 2, c6 = hs^3 s0 / 6), c1 = 0, and the highest ones
    match the value p0 + dp, rate r1, acceleration q1 (and jerk s1) at x = 1.

    - ``septic`` (linear-dashpot laws, jerks known): the singular terms start at x^7, the
      Hertz (t - t_ref)^{7/2}; c7..c10 from the four end data. Exact for the regular part
      to (t - t_ref)^5 and the singular terms (t - t_ref)^{7/2}, (t - t_ref)^{9/2}.
    - else (Kuwabara-Kono: its jerk is unbounded at t_ref and the singular terms start at
      x^5): c5..c7 from value, rate and acceleration at x = 1.
    """
    hh = hs * hs
    c2 = hs * r0
    c4 = 0.5 * hh * q0
    # Value and first (three) x-derivatives at x = 1 left for the highest coefficients;
    # their inverse systems in exact rationals.
    if septic:
        c6 = hh * hs * s0 / 6.0
        e0 = dp - c2 - c4 - c6
        e1 = 2.0 * hs * r1 - 2.0 * c2 - 4.0 * c4 - 6.0 * c6
        e2 = 2.0 * hs * r1 + 4.0 * hh * q1 - 2.0 * c2 - 12.0 * c4 - 30.0 * c6
        e3 = 12.0 * hh * q1 + 8.0 * hh * hs * s1 - 24.0 * c4 - 120.0 * c6
        return (p0, c2, 0.0, c4, 0.0, c6,
                120.0 * e0 - 36.0 * e1 + 4.0 * e2 - e3 / 6.0,
                -315.0 * e0 + 99.0 * e1 - 11.5 * e2 + 0.5 * e3,
                280.0 * e0 - 91.0 * e1 + 11.0 * e2 - 0.5 * e3,
                -84.0 * e0 + 28.0 * e1 - 3.5 * e2 + e3 / 6.0)
    e0 = dp - c2 - c4
    e1 = 2.0 * hs * r1 - 2.0 * c2 - 4.0 * c4
    e2 = 2.0 * hs * r1 + 4.0 * hh * q1 - 2.0 * c2 - 12.0 * c4
    return (p0, c2, 0.0, c4, 21.0 * e0 - 6.0 * e1 + 0.5 * e2, -35.0 * e0 + 11.0 * e1 - e2,
            15.0 * e0 - 5.0 * e1 + 0.5 * e2, 0.0, 0.0, 0.0)


@nb.njit(cache=True, inline="always")
def _sqrt_gap_coefficients(k, septic, hs, ur, vr, ar, jr, uo, vo, ao, jo):
    """:func:`_sqrt_coefficients` of contact k's gap from the particle end data (r: at the
    singular end, o: at the other)."""
    g0 = ur[k] - ur[k + 1]
    return _sqrt_coefficients(septic, hs, g0, vr[k] - vr[k + 1], ar[k] - ar[k + 1],
                              jr[k] - jr[k + 1], (uo[k] - uo[k + 1]) - g0, vo[k] - vo[k + 1],
                              ao[k] - ao[k + 1], jo[k] - jo[k + 1])


@nb.njit(cache=True, inline="always")
def _put_column(cs, c, coef):
    # The ten coefficients into column c of cs.
    cs[0, c] = coef[0]
    for q in range(1, 10):
        cs[q, c] = coef[q]


@nb.njit(cache=True, inline="always")
def _sqrt_value(cs, k, x, inv_2hs):
    """Value and time derivative at x of the interpolant in x = sqrt((t - t_ref) / hs) in
    column k of ``cs`` (see :func:`_sample_sqrt`)."""
    # value c0 + x^2 (c2 + c3 x + ... + c10 x^8) (cs[q] = c_{q+1}, c1 = 0); rate =
    # (d/dx) / (dt/dx = 2 hs x) = (2 c2 + 3 c3 x + ... + 10 c10 x^8) / (2 hs)
    g = cs[9, k]
    d = 10.0 * cs[9, k]
    for q in range(8, 0, -1):
        g = g * x + cs[q, k]
        d = d * x + (q + 1) * cs[q, k]
    return cs[0, k] + x * x * g, d * inv_2hs


@nb.njit(cache=True, fastmath=_FM)
def _sample_sqrt(t_out, j, t0, h, mode, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                 store_uv, out_F, out_d, out_u, out_v, us, vs, Fp, cs, sel, subset):
    """:func:`_sample` for a step taken in a square-root time variable (``mode``).

    The interpolant is the Hermite polynomial in x = sqrt((t - t_ref) / hs): t_ref = t0, hs = h
    for ``STEP_SQRT_START`` (a contact closed at t0), t_ref = t0 + h, hs = -h for
    ``STEP_SQRT_END`` (one opens at t0 + h). In x the solution is smooth (see
    :mod:`msens.chain.dop853_codegen`), in t it is not. Rates are d/dx over dt/dx = 2 hs x,
    taken from the polynomial with its x^1 term zero (no division by x). ``cs`` (10, p + 1)
    receives the coefficients (c0, c2..c10, per contact or, with ``store_uv``, per particle);
    with ``subset`` only the contacts ``sel`` are sampled.
    """
    m = cA.shape[0]
    nt = t_out.shape[0]
    hkk = law == LAW_HKK
    if mode == STEP_SQRT_START:
        t_ref, hs = t0, h
        ur, vr, ar, jr, uo, vo, ao, jo = u0, v0, a0, j0, u1, v1, a1, j1
    else:
        t_ref, hs = t0 + h, -h
        ur, vr, ar, jr, uo, vo, ao, jo = u1, v1, a1, j1, u0, v0, a0, j0
    # Per particle (states wanted) or directly per contact gap (linear in the end data): the
    # coefficients of contact sel[c] go to column c (a subset) or of contact k to column k.
    cols = m + 1 if store_uv else m
    if store_uv:
        for k in range(cols):
            _put_column(cs, k, _sqrt_coefficients(septic, hs, ur[k], vr[k], ar[k], jr[k],
                                                  uo[k] - ur[k], vo[k], ao[k], jo[k]))
    elif subset:
        for c in range(sel.shape[0]):
            _put_column(cs, c, _sqrt_gap_coefficients(sel[c], septic, hs, ur, vr, ar, jr, uo,
                                                      vo, ao, jo))
    else:
        for k in range(cols):
            _put_column(cs, k, _sqrt_gap_coefficients(k, septic, hs, ur, vr, ar, jr, uo, vo,
                                                      ao, jo))
    inv_2hs = 0.5 / hs
    while j < nt and t_out[j] <= t0 + h:
        x = np.sqrt(max((t_out[j] - t_ref) / hs, 0.0))
        if store_uv:
            for k in range(cols):
                us[k], vs[k] = _sqrt_value(cs, k, x, inv_2hs)
            j = _store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel)
        elif subset:
            for c in range(sel.shape[0]):
                k = sel[c]
                g, r = _sqrt_value(cs, c, x, inv_2hs)
                out_d[j, c] = g
                out_F[j, c] = _force(g, r, cA[k], cg[k], hkk)
            j += 1
        else:
            for k in range(cols):
                g, r = _sqrt_value(cs, k, x, inv_2hs)
                out_d[j, k] = g
                out_F[j, k] = _force(g, r, cA[k], cg[k], hkk)
            j += 1
    return j


@nb.njit(cache=True, inline="always")
def _closing_grade(r, q, levels):
    """Grading depth after a contact closed at approach rate r and relative acceleration q
    (both times powers of the nominal step: r dt, q dt^2): at least ``levels``, deeper while
    the first step dt 2^-g exceeds _CLOSE_FRAC of the time 2 |r| / |q| over which the rate
    changes by itself (a slow, grazing closing: there the expansion in sqrt(t - t0)
    converges only over that time)."""
    g = levels
    while g < _CLOSE_MAX and _CLOSE_FRAC * 2.0 * abs(r) < abs(q) * 0.5**g:
        g += 1
    return g


@nb.njit(cache=True)
def _store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel):
    # Forces and approaches of the contacts sel (and with store_uv the states) of row j from
    # (us, vs).
    m = cA.shape[0]
    contact_forces(us, vs, cA, cg, law, Fp)
    for c in range(sel.shape[0]):
        k = sel[c]
        out_F[j, c] = Fp[k + 1]
        out_d[j, c] = us[k] - us[k + 1]
    if store_uv:
        for k in range(m):
            out_u[j, k] = us[k]
            out_v[j, k] = vs[k]
    return j + 1


@nb.njit(cache=True, fastmath=_FM)
def _update_near(k, u, v, a, jk, with_jerk, cA, cg, law, load, inv_m):
    """After contact k switched: the accelerations of its two particles (and with
    ``with_jerk`` the jerks of the four around it) anew, the only ones that change; the same
    arithmetic as :func:`accelerations` and :func:`jerks` (padded layout)."""
    p = cA.shape[0]
    hkk = law == LAW_HKK
    # Each contact's force (and its rate) once, carried over as in the full passes.
    f_prev = 0.0
    if k > 0:
        f_prev = _force(u[k - 1] - u[k], v[k - 1] - v[k], cA[k - 1], cg[k - 1], hkk)
    for i in range(k, min(k + 2, p)):
        f = _force(u[i] - u[i + 1], v[i] - v[i + 1], cA[i], cg[i], hkk)
        a[i] = (load[i] + f_prev - f) * inv_m[i]
        f_prev = f
    if with_jerk:
        i0 = max(k - 1, 0)
        d_prev = 0.0
        if i0 > 0:
            d_prev = _dforce(u[i0 - 1] - u[i0], v[i0 - 1] - v[i0], a[i0 - 1] - a[i0],
                             cA[i0 - 1], cg[i0 - 1])
        for i in range(i0, min(k + 3, p)):
            d = _dforce(u[i] - u[i + 1], v[i] - v[i + 1], a[i] - a[i + 1], cA[i], cg[i])
            jk[i] = (d_prev - d) * inv_m[i]
            d_prev = d


@nb.njit(cache=True, inline="always")
def _opening_time(g, r, q, closed):
    # Time until a closed contact opens, from its gap's Taylor quadratic g + r tau + q tau^2 / 2
    # (gap g, rate r, relative acceleration q): the smallest positive root, in a form without
    # cancellation; inf if it does not open on that estimate. Scalars and no branches. (LLVM
    # leaves the min-reduction over contacts scalar, also over padded arrays with fast-math:
    # _openings_within spares most steps from it.)
    disc = r * r - 2.0 * q * g
    tau = 2.0 * g / max(np.sqrt(max(disc, 0.0)) - r, 1e-300)
    return tau if (closed > 0.0 and r < 0.0 and disc >= 0.0) else np.inf


@njit_noalias(cache=True, fastmath=_FM)
def _violated(u1, v1, closed, damp, gam, rate_tol, loading, skip):
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


@njit_noalias(cache=True, fastmath=_FM)
def _openings_within(u, v, a, closed, T, flag):
    """Flags (1.0) into ``flag`` (p,) the closed contacts that may open within time T, and
    returns their number: a superset (by a relative margin of 1e-6) of those with
    :func:`_opening_time` < T, found without its square root and division (2 g / (sqrt(disc)
    - r) < T <=> 2 g + T r < T sqrt(disc)) so that the pass vectorises; padded ``closed`` as
    in :func:`_violated`. Only flagged contacts then need the least time (on the paper chain
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


@njit_noalias(cache=True, fastmath=_FM)
def _switch_candidates(v, a, closed, damp, gam, rate_tol, two_h, flag):
    """Flags (1.0) into ``flag`` (p,) the closed contacts with a dashpot whose approach rate
    is above the noise floor, of the sign their dashpot state allows (not one that just
    switched, within its tolerance) and closing in on zero within ``two_h`` on a linear
    estimate; returns their number. Branch-free over the padded arrays (vectorised); the
    predictor then visits only these (before, the scan over all contacts with these tests
    as branches took a sixth of the run time)."""
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
def _gap_tol(k, closed, damp, gam, hkk):
    # Tolerance of the switch time of contact k's gap state, in steps (see _GAP_TOL).
    smooth = hkk or gam[k] == 0.0 or (closed[k] > 0.0 and damp[k] == 0.0)
    return _GAP_TOL_SMOOTH if smooth else _GAP_TOL


@nb.njit(cache=True)
def _switch(kind, k, t, u, v, a, jk, jk_ok, closed, damp, A, gam, cA, cg, law, load, inv_m,
            t_left, q_left, s_left):
    """Switch contact k's state at time t (``kind`` as in :func:`_toggle`) and update the
    accelerations (and valid jerks) that change. With the loading law the relative
    accelerations and jerks of the contacts around k just before the first switch at t are
    kept (``q_left``, ``s_left``, ``t_left`` = t) for the switch predictor, and the jerks are
    formed first if not valid. Returns (whether it closed, whether the jerks are valid)."""
    if law == LAW_LINEAR_LOADING:
        if not jk_ok:
            jerks(u, v, a, cA, cg, inv_m, jk)
            jk_ok = True
        # A switch of contact k moves the accelerations of its two particles and the jerks of
        # the four around it: the relative ones of contacts k - 2 .. k + 2.
        for i in range(max(k - 2, 0), min(k + 3, t_left.shape[0])):
            if t_left[i] != t:
                t_left[i] = t
                q_left[i] = a[i] - a[i + 1]
                s_left[i] = jk[i] - jk[i + 1]
    closing = _toggle(kind, k, closed, damp, A, gam, cA, cg)
    _update_near(k, u, v, a, jk, jk_ok and law != LAW_HKK, cA, cg, law, load, inv_m)
    return closing, jk_ok


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
              store_uv, out_F, out_d, out_u, out_v, sel):
    """Integrate one chain from t = 0 over t_out (sorted, t_out[0] >= 0) with nominal step dt.

    ``grade_levels`` is the depth K of the step grading after a contact closes (first step,
    in sqrt(t - t0), dt 2^-K); ``rate_tol`` (m/s) the approach rate below which a sign change
    of the rate is not an event (the loading-only dashpot then errs by at most
    gamma * rate_tol).

    Fills out_F, out_d with the forces and approaches of the contacts ``sel`` (int64, (c,)),
    each (nt, c): all contacts are ``sel`` = 0, ..., p - 1 with p = n rounded up to a multiple
    of ``_PAD`` (columns past n come out 0), through full-width vector loops; any other
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
    inv_m = _zeros64(p)
    inv_m[:n] = 1.0 / mass
    load_p = _zeros64(p)
    load_p[:n] = load
    u = _zeros64(m)
    v = _zeros64(m)
    u[:n] = u_init
    v[:n] = v_init
    u1 = _zeros64(m)
    v1 = _zeros64(m)
    a0 = _zeros64(m)
    a1 = _zeros64(m)
    kv = _zeros64_rows(N_STAGES, m)
    tu = _zeros64(m)
    tv = _zeros64(m)
    F = _zeros64(m)
    us = _zeros64(m)
    cs = _zeros64_rows(10, m)
    j0 = _zeros64(m)
    j1 = _zeros64(m)
    vs = _zeros64(m)
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
    closed = _zeros64(p)
    damp = _zeros64(p)
    gam_p = _zeros64(p)
    gam_p[:n] = gam
    flag = _zeros64(p)
    cA = _zeros64(p)
    cg = _zeros64(p)
    loading = law == LAW_LINEAR_LOADING
    hkk = law == LAW_HKK
    # Septic dense output from the jerks (the Kuwabara-Kono jerk is unbounded at contact
    # switches: quintic there).
    septic = not hkk
    for k in range(n):
        g = _gap(u, k)
        r = _gap(v, k)
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
        j = _sample(t_out, j, -1.0, 1.0, 0.0, u, v, a0, j0, u, v, a0, j0, cA, cg, law, septic,
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
        if closed[k] > 0.0 and _gap(u, k) == 0.0:
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
        # _opening_time). Opening within the step: the step ends there, taken in
        # sqrt(t0 - t) (the Newton refinement of its length follows the step); within two
        # steps: half-way first.
        tau_min = 2.0 * h
        if _openings_within(u, v, a0, closed, tau_min, flag) > 0:
            for k in range(n):
                if flag[k] > 0.0:
                    tau_min = min(tau_min, _opening_time(u[k] - u[k + 1], v[k] - v[k + 1],
                                                         a0[k] - a0[k + 1], closed[k]))
        k_open = -1
        h_end = _END_FRAC * dt
        if tau_min < 2.0 * h:
            if not sqrt_start and tau_min > min(h, 1.5 * h_end):
                # Approach in halving steps (each as long as the distance left at its end).
                h = 0.5 * tau_min
            elif not sqrt_start:
                # Which contact (a scalar pass, as rare as openings).
                h_open = 2.0 * h
                for k in range(n):
                    tau = _opening_time(_gap(u, k), _gap(v, k), _gap(a0, k), closed[k])
                    if tau < h_open:
                        h_open = tau
                        k_open = k
                if k_open >= 0:
                    h = h_open
                    mode = STEP_SQRT_END
                if k_open >= 0 and h <= _THETA_NOW * dt and toggles_here < 4 * n:
                    # Opening now.
                    toggles_here += 1
                    _, j0_ok = _switch(0, k_open, t, u, v, a0, j0, j0_ok, closed, damp, A, gam,
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
            h_max = h * (1.0 + _PRED_STRETCH)
            # Candidates (see _switch_candidates); of equal predicted times the first wins.
            if _switch_candidates(v, a0, closed, damp, gam_p, rate_tol, 2.0 * h, flag) > 0:
                for k in range(n):
                    if flag[k] == 0.0:
                        continue
                    r = _gap(v, k)
                    q = _gap(a0, k)
                    sk = _gap(j0, k)
                    left = t_left[k] == t
                    tau = _rate_zero(r, q, sk, q_left[k] if left else q,
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
            if k_pred >= 0 and h <= _PRED_TOL * dt and toggles_here < 4 * n:
                # The switch is due now.
                toggles_here += 1
                _, j0_ok = _switch(1, k_pred, t, u, v, a0, j0, j0_ok, closed, damp, A, gam, cA,
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
        tol = _gap_tol(k_open, closed, damp, gam, hkk) if k_open >= 0 else 0.0
        for it in range(_NEWTON_MAX + 2):
            rk_step(u, v, a0, h, mode, cA, cg, hkk, load_p, inv_m, kv, tu, tv, u1, v1)
            steps += 1
            if k_open < 0:
                break
            g = _gap(u1, k_open)
            r = _gap(v1, k_open)
            if abs(g) <= tol * h * abs(r):
                break
            hn = h - g / r if r < 0.0 else -1.0
            if it >= _NEWTON_MAX or not 0.0 < hn <= 2.0 * h_first:
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
        bad = _violated(u1, v1, closed, damp, gam_p, rate_tol, loading, k_pred)
        for k in range(0 if bad else max(k_pred, 0), n if bad else k_pred + 1):
            if k == k_open:
                continue  # opens at the step's end (below)
            g1 = _gap(u1, k)
            if (closed[k] > 0.0 and g1 < 0.0) or (closed[k] == 0.0 and g1 > 0.0):
                th = _first_violation(_gap(u, k), h * _gap(v, k), g1,
                                      h * _gap(v1, k), closed[k] > 0.0)
                if th < th_min:
                    th_min = th
                    kmin = k
                    kind = 0
            elif loading and closed[k] > 0.0 and gam[k] > 0.0:
                # (a contact without dashpot has no dashpot switches to track)
                r1 = _gap(v1, k)
                if (damp[k] > 0.0 and r1 < -rate_tol) or (damp[k] == 0.0 and r1 > rate_tol):
                    if k == k_pred and _hermite3(
                            (1.0 - 2.0 * damp[k]) * _gap(v, k),
                            (1.0 - 2.0 * damp[k]) * h * _gap(a0, k),
                            (1.0 - 2.0 * damp[k]) * r1, (1.0 - 2.0 * damp[k]) * h * _gap(a1, k),
                            1.0 - _PRED_TOL) <= 0.0:
                        # The predicted switch: the rate's sign is still the allowed one at
                        # 1 - _PRED_TOL, so it changes at the step's end. Accepted below.
                        continue
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
                closing, j0_ok = _switch(kind, kmin, t, u, v, a0, j0, j0_ok, closed, damp, A,
                                         gam, cA, cg, law, load_p, inv_m, t_left, q_left,
                                         s_left)
                if closing:
                    sqrt_start = True
                    t_close = t
                    grade = _closing_grade(_gap(v, kmin) * dt, _gap(a0, kmin) * dt * dt,
                                           grade_levels)
                continue
            if th_min > _THETA_NOW:
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
                tol = _gap_tol(kmin, closed, damp, gam, hkk) if kmin >= 0 else 0.0
                for it in range(_NEWTON_MAX + 1):
                    rk_step(u, v, a0, hc, mode, cA, cg, hkk, load_p, inv_m, kv, tu, tv, u1,
                            v1)
                    steps += 1
                    if kmin < 0:
                        if loading:
                            accelerations(u1, v1, cA, cg, law, load_p, inv_m, a1)
                        break
                    if it == _NEWTON_MAX or kind == 1:
                        # A rate switch is only a kink of the force: the cubic estimate of its
                        # time (error O(h^4)) is ample, no Newton refinement.
                        break
                    g = _gap(u1, kmin)
                    r = _gap(v1, kmin)
                    if abs(g) <= tol * h * abs(r) or r == 0.0:
                        break
                    hn = hc - g / r
                    if hn <= 0.0 or hn > h:
                        break
                    hc = hn
                # (u1, v1) is the state at t + hc.
                h = hc
                if redo_here < 4 and _violated(u1, v1, closed, damp, gam_p, rate_tol, loading,
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
            # _PRED_TOL steps of it (either side); otherwise the prediction fell short.
            r1 = _gap(v1, k_pred)
            q1 = _gap(a1, k_pred)
            crossed = r1 < 0.0 if damp[k_pred] > 0.0 else r1 > 0.0
            if not (crossed or abs(r1) <= _PRED_TOL * h * abs(q1)):
                k_pred = -1
        else:
            k_pred = -1
        if loading:
            for k in range(n):
                r_prev[k] = _gap(v, k)
                q_prev[k] = _gap(a0, k)
                s_prev[k] = _gap(j0, k)
            h_prev = h
        j1_ok = False
        if septic and j < nt and t_out[j] <= t + h:
            if not j0_ok:
                jerks(u, v, a0, cA, cg, inv_m, j0)
            jerks(u1, v1, a1, cA, cg, inv_m, j1)
            j1_ok = True
        if mode == STEP_REGULAR or h < 1e-3 * dt:
            j = _sample(t_out, j, t, h, 1e-3 * dt, u, v, a0, j0, u1, v1, a1, j1, cA, cg, law,
                        septic, store_uv, out_F, out_d, out_u, out_v, us, vs, F, cs, sel,
                        subset)
        elif j < nt and t_out[j] <= t + h:
            j = _sample_sqrt(t_out, j, t, h, mode, u, v, a0, j0, u1, v1, a1, j1, cA, cg, law,
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
        if kmin >= 0 and th_min > _THETA_NOW:
            k_tog = kmin
            kind_tog = kind
        elif k_open >= 0:
            k_tog = k_open
        elif k_pred >= 0:
            k_tog = k_pred
            kind_tog = 1
        if k_tog >= 0:
            sqrt_start, j0_ok = _switch(kind_tog, k_tog, t, u, v, a0, j0, j0_ok, closed, damp, A,
                                        gam, cA, cg, law, load_p, inv_m, t_left, q_left, s_left)
            if sqrt_start:
                t_close = t
                grade = _closing_grade(_gap(v, k_tog) * dt, _gap(a0, k_tog) * dt * dt,
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
