"""Dense output of the chain kernel: contact forces and approaches at the output times.

The interpolant of a regular step is the septic Hermite polynomial through the displacement,
velocity, acceleration and jerk at the two ends of the step (error O(h^8) in u, O(h^7) in
v); the Kuwabara-Kono law, whose jerk is unbounded where a contact switches, keeps the
quintic through (u, v, a). When only forces and approaches are wanted the interpolant is
applied directly to the gaps and approach rates (it is linear in the end data), fused with
the force law. A step taken in a square-root time variable is interpolated in that variable
(:func:`sample_sqrt`). Helpers called inside the sampling loops take scalars, not arrays
(numba's reference counting of array arguments of inlined helpers stops those loops from
vectorising).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain.kernel.dop853_step import STEP_SQRT_START
from msens.chain.kernel.forces import FM, LAW_HKK, contact_forces, force
from msens.chain.kernel.hermite import (
    hermite_coefficients,
    hermite_weights,
    sqrt_coefficients,
)
from msens.chain.kernel.noalias import njit_noalias

# Steps with at most this many output samples evaluate the interpolant from its weights;
# more amortise forming its monomial coefficients.
_FEW_SAMPLES = 3


@nb.njit(cache=True, inline="always")
def sample(t_out, j, t0, h, tiny, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
            store_uv, out_F, out_d, out_u, out_v, us, vs, Fp, cs, sel, subset):
    """Write the dense-output samples with t0 < t_out[j] <= t0 + h; return the next j.

    The interpolant is the Hermite polynomial through the states, accelerations and (with
    ``septic``) jerks ``j0``/``j1`` at both ends of the step: septic, error O(h^8) in the
    gaps, O(h^7) in their rates; else quintic (O(h^6), O(h^5)). Padded layout (see
    :func:`contact_forces`): column c of ``out_F`` and ``out_d`` is contact ``sel[c]``, all
    contacts in order (``sel`` = 0, ..., p - 1, entries past n come out 0) unless
    ``subset``. ``us``, ``vs``, ``Fp`` (p + 1,) and ``cs`` (>= 8, p + 1) are scratch. Without
    ``store_uv`` the interpolant is applied directly to the contact gaps (it is linear in the
    end data), fused with the force law (:func:`sample_gaps`); with ``store_uv``, or in a
    sliver step shorter than ``tiny``, per particle (:func:`_sample_states`).
    """
    if j >= t_out.shape[0] or t_out[j] > t0 + h:
        return j
    if store_uv or h < tiny:
        return _sample_states(t_out, j, t0, h, tiny, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg,
                              law, septic, store_uv, out_F, out_d, out_u, out_v, us, vs, Fp,
                              sel)
    if subset:
        return sample_contacts(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law,
                                septic, out_F, out_d, cs, sel)
    return sample_gaps(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                        out_F, out_d, cs)


@nb.njit(cache=True, fastmath=FM)
def _sample_states(t_out, j, t0, h, tiny, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                   store_uv, out_F, out_d, out_u, out_v, us, vs, Fp, sel):
    """:func:`sample` per particle: the states at each sample, then their forces."""
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
            j = store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel)
        return j
    inv_h = 1.0 / h
    while j < nt and t_out[j] <= t0 + h:
        (w_dp, w_r0, w_r1, w_q0, w_q1, w_s0, w_s1,
         v_dp, v_r0, v_r1, v_q0, v_q1, v_s0, v_s1) = hermite_weights(
            septic, (t_out[j] - t0) * inv_h, h)
        for i in range(m + 1):
            du = u1[i] - u0[i]
            us[i] = (u0[i] + w_dp * du + w_r0 * v0[i] + w_r1 * v1[i] + w_q0 * a0[i]
                     + w_q1 * a1[i] + w_s0 * j0[i] + w_s1 * j1[i])
            vs[i] = (v_dp * du + v_r0 * v0[i] + v_r1 * v1[i] + v_q0 * a0[i]
                     + v_q1 * a1[i] + v_s0 * j0[i] + v_s1 * j1[i])
        j = store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel)
    return j


@nb.njit(cache=True, inline="always")
def _gap_sample(k, w, u0, v0, a0, j0, u1, v1, a1, j1):
    """Gap and gap rate of contact k at a sample, from the weights ``w`` of
    :func:`hermite_weights` (the interpolant is linear in the end data)."""
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
    :func:`sample`) into column c of ``cs`` (rows 0-7)."""
    g0 = u0[k] - u0[k + 1]
    c1, c2, c3, c4, c5, c6, c7 = hermite_coefficients(
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
    # arithmetic, bound the sampling loop).
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


@njit_noalias(cache=True, fastmath=FM)
def sample_gaps(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic, out_F,
                 out_d, cs):
    """:func:`sample` on the contact gaps: in steps with more than ``_FEW_SAMPLES`` samples
    through the interpolant's eight monomial coefficients in s = tau / h (formed once per
    step into ``cs``; the rate is the derivative), else through the weights of the end data
    at each sample."""
    m = cA.shape[0]
    hkk = law == LAW_HKK
    inv_h = 1.0 / h
    ns = _samples_in(t_out, j, t0 + h)
    if ns <= _FEW_SAMPLES:
        for _ in range(ns):
            w = hermite_weights(septic, (t_out[j] - t0) * inv_h, h)
            for k in range(m):
                g, r = _gap_sample(k, w, u0, v0, a0, j0, u1, v1, a1, j1)
                out_d[j, k] = g
                out_F[j, k] = force(g, r, cA[k], cg[k], hkk)
            j += 1
        return j
    for k in range(m):
        _gap_coefficients(cs, k, k, septic, h, h * h, u0, v0, a0, j0, u1, v1, a1, j1)
    for _ in range(ns):
        x = (t_out[j] - t0) * inv_h
        for k in range(m):
            g, d = _horner(cs, k, x)
            out_d[j, k] = g
            out_F[j, k] = force(g, d * inv_h, cA[k], cg[k], hkk)
        j += 1
    return j


@njit_noalias(cache=True, fastmath=FM)
def sample_contacts(t_out, j, t0, h, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                     out_F, out_d, cs, sel):
    """:func:`sample_gaps` for the contacts ``sel`` only (column c = contact sel[c]), with
    the same arithmetic per contact (so the same values)."""
    hkk = law == LAW_HKK
    inv_h = 1.0 / h
    ns = _samples_in(t_out, j, t0 + h)
    cols = sel.shape[0]
    if ns <= _FEW_SAMPLES:
        for _ in range(ns):
            w = hermite_weights(septic, (t_out[j] - t0) * inv_h, h)
            for c in range(cols):
                k = sel[c]
                g, r = _gap_sample(k, w, u0, v0, a0, j0, u1, v1, a1, j1)
                out_d[j, c] = g
                out_F[j, c] = force(g, r, cA[k], cg[k], hkk)
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
            out_F[j, c] = force(g, d * inv_h, cA[k], cg[k], hkk)
        j += 1
    return j


@nb.njit(cache=True, inline="always")
def _sqrt_gap_coefficients(k, septic, hs, ur, vr, ar, jr, uo, vo, ao, jo):
    """:func:`sqrt_coefficients` of contact k's gap from the particle end data (r: at the
    singular end, o: at the other)."""
    g0 = ur[k] - ur[k + 1]
    return sqrt_coefficients(septic, hs, g0, vr[k] - vr[k + 1], ar[k] - ar[k + 1],
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
    column k of ``cs`` (see :func:`sample_sqrt`)."""
    # value c0 + x^2 (c2 + c3 x + ... + c10 x^8) (cs[q] = c_{q+1}, c1 = 0); rate =
    # (d/dx) / (dt/dx = 2 hs x) = (2 c2 + 3 c3 x + ... + 10 c10 x^8) / (2 hs)
    g = cs[9, k]
    d = 10.0 * cs[9, k]
    for q in range(8, 0, -1):
        g = g * x + cs[q, k]
        d = d * x + (q + 1) * cs[q, k]
    return cs[0, k] + x * x * g, d * inv_2hs


@nb.njit(cache=True, fastmath=FM)
def sample_sqrt(t_out, j, t0, h, mode, u0, v0, a0, j0, u1, v1, a1, j1, cA, cg, law, septic,
                 store_uv, out_F, out_d, out_u, out_v, us, vs, Fp, cs, sel, subset):
    """:func:`sample` for a step taken in a square-root time variable (``mode``).

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
            _put_column(cs, k, sqrt_coefficients(septic, hs, ur[k], vr[k], ar[k], jr[k],
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
            j = store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel)
        elif subset:
            for c in range(sel.shape[0]):
                k = sel[c]
                g, r = _sqrt_value(cs, c, x, inv_2hs)
                out_d[j, c] = g
                out_F[j, c] = force(g, r, cA[k], cg[k], hkk)
            j += 1
        else:
            for k in range(cols):
                g, r = _sqrt_value(cs, k, x, inv_2hs)
                out_d[j, k] = g
                out_F[j, k] = force(g, r, cA[k], cg[k], hkk)
            j += 1
    return j


@nb.njit(cache=True)
def store(j, us, vs, cA, cg, law, store_uv, out_F, out_d, out_u, out_v, Fp, sel):
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
