"""The generated, unrolled DOP853 step against its generator, against SciPy's own step, and its
local order."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate._ivp import dop853_coefficients as dop
from scipy.integrate._ivp.rk import rk_step as scipy_rk_step

from msens.chain import dop853_codegen, kernel
from msens.chain.kernel import dop853_step


def test_committed_module_is_the_generator_output():
    """Text equality holds on every machine: the generator's numbers are exactly rounded (next
    test), so they do not depend on the CPU's float sums or BLAS."""
    assert dop853_codegen.TARGET.read_text() == dop853_codegen.step_source()


def test_generated_coefficients_are_the_exactly_rounded_products():
    """Every number of the three tableaus equals the exact value of its defining sum or product
    of SciPy's doubles, rounded once to the nearest double. Reference: mpmath at 2000 bits,
    where these sums of products of doubles are exact (a float evaluation differs from it by
    up to 7.6e-12 relative, in 170 of the 378 generated numbers)."""
    import mpmath

    s_count = dop.N_STAGES
    tab = dop853_codegen.tableaus()
    with mpmath.workprec(2000):
        a = [[mpmath.mpf(float(x)) for x in row] for row in dop.A[:s_count, :s_count]]
        b = [mpmath.mpf(float(x)) for x in dop.B]
        c = [sum(row) for row in a]
        rng = range(s_count)
        for mode, w in enumerate((None, [2 * x for x in c], [2 * (1 - x) for x in c])):
            aw = a if w is None else [[a[i][j] * w[j] for j in rng] for i in rng]
            bw = b if w is None else [b[j] * w[j] for j in rng]
            ref = {"ch": [sum(row) for row in aw],
                   "au": [[sum(aw[i][k] * aw[k][j] for k in rng) for j in rng] for i in rng],
                   "av": aw,
                   "bu": [sum(bw[k] * aw[k][j] for k in rng) for j in rng],
                   "bv": bw}
            for key, x in ref.items():
                np.testing.assert_array_equal(tab[key][mode], np.vectorize(float)(np.array(x)),
                                              err_msg=f"{key}, mode {mode}")


@pytest.mark.parametrize("law", [kernel.LAW_LINEAR, kernel.LAW_HKK])
def test_step_matches_scipy_dop853_step(law):
    """One step of the padded second-order form equals SciPy's DOP853 step on the first-order
    system (u, v)' = (v, a(u, v)), tube drag included, to rounding (measured: 6e-14 relative
    on the displacement increments, 4e-15 on the velocities)."""
    n = 11
    p = kernel.padded_length(n)
    rng = np.random.default_rng(5)
    mass = rng.uniform(0.02, 0.03, n)
    A = rng.uniform(5e9, 1e10, n)
    gam = rng.uniform(1.0, 5.0, n)
    load = rng.uniform(0.1, 0.3, n)
    # every contact closed, approaches ~1 um, and distinct velocities
    u0 = np.cumsum(rng.uniform(0.5e-6, 1.5e-6, n))[::-1].copy()
    v0 = rng.uniform(-0.05, 0.05, n)
    pad = np.zeros(p + 1)
    u, v = pad.copy(), pad.copy()
    u[:n], v[:n] = u0, v0
    cA, cg, load_p, inv_m, drag = (np.zeros(p) for _ in range(5))
    cA[:n], cg[:n], load_p[:n], inv_m[:n] = A, gam, load, 1.0 / mass
    # tube drag c/m (1/s), strong enough to move the step by far more than rounding
    drag[:n] = rng.uniform(1e3, 1e4, n)

    def acc(uu, vv):
        out = np.zeros(p + 1)
        kernel.accelerations(uu, vv, cA, cg, law, load_p, inv_m, drag, out)
        return out

    a0 = acc(u, v)
    h = 1.5e-6
    kv = np.zeros((dop853_step.N_STAGES, p + 1))
    u1, v1 = pad.copy(), pad.copy()
    dop853_step.rk_step(u, v, a0, h, dop853_step.STEP_REGULAR, cA, cg, law == kernel.LAW_HKK,
                         load_p, inv_m, drag, kv, pad.copy(), pad.copy(), u1, v1)

    def rhs(_t, y):
        uu, vv = pad.copy(), pad.copy()
        uu[:n], vv[:n] = y[:n], y[n:]
        return np.concatenate([y[n:], acc(uu, vv)[:n]])

    y0 = np.concatenate([u0, v0])
    K = np.empty((dop.N_STAGES + 1, 2 * n))
    y1, _ = scipy_rk_step(rhs, 0.0, y0, rhs(0.0, y0), h, dop.A[:dop.N_STAGES, :dop.N_STAGES],
                          dop.B, dop.C[:dop.N_STAGES], K)
    np.testing.assert_allclose(u1[:n] - u0, y1[:n] - u0, rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(v1[:n], y1[n:], rtol=1e-12, atol=1e-18)
    assert np.all(u1[n:] == 0.0) and np.all(v1[n:] == 0.0)  # the padding stays zero


def _random_chain(n=11, seed=5):
    """Padded arrays of a random all-closed chain: state, coefficients and an acceleration."""
    p = kernel.padded_length(n)
    rng = np.random.default_rng(seed)
    pad = np.zeros(p + 1)
    u, v = pad.copy(), pad.copy()
    u[:n] = np.cumsum(rng.uniform(0.5e-6, 1.5e-6, n))[::-1]
    v[:n] = rng.uniform(-5e-3, 5e-3, n)  # slow: the contacts stay closed over the steps
    cA, cg, load, inv_m, drag = (np.zeros(p) for _ in range(5))
    cA[:n] = rng.uniform(5e9, 1e10, n)
    cg[:n] = rng.uniform(1.0, 5.0, n)
    load[:n] = rng.uniform(0.1, 0.3, n)
    inv_m[:n] = 1.0 / rng.uniform(0.02, 0.03, n)
    drag[:n] = rng.uniform(0.0, 1e3, n)  # tube drag c/m, 1/s
    return u, v, cA, cg, load, inv_m, drag


def test_local_error_is_ninth_order():
    """One step from the same state: the error against 64 substeps scales as h^9 (measured
    slope 8.8 over omega h ~ 0.25-0.5; asserted within [8.5, 9.5])."""
    u, v, cA, cg, load, inv_m, drag = _random_chain()
    m = u.size
    kv = np.zeros((dop853_step.N_STAGES, m))

    def one(fn, uu, vv, h):
        a0 = np.zeros(m)
        kernel.accelerations(uu, vv, cA, cg, kernel.LAW_LINEAR, load, inv_m, drag, a0)
        u1, v1 = np.zeros(m), np.zeros(m)
        fn(uu, vv, a0, h, dop853_step.STEP_REGULAR, cA, cg, False, load, inv_m, drag, kv,
           np.zeros(m), np.zeros(m), u1, v1)
        return u1, v1

    def fine(h):
        uu, vv = u.copy(), v.copy()
        for _ in range(64):
            uu, vv = one(dop853_step.rk_step, uu, vv, h / 64)
        return vv

    hs = np.array([2e-5, 1.5e-5, 1e-5])  # omega h ~ 0.5 for the stiffest mode
    errs = [np.max(np.abs(one(dop853_step.rk_step, u, v, h)[1] - fine(h))) for h in hs]
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert 8.5 <= slope <= 9.5, (slope, errs)


@pytest.mark.parametrize("mode", [dop853_step.STEP_SQRT_START, dop853_step.STEP_SQRT_END])
def test_sqrt_modes_are_dop853_in_the_square_root_of_time(mode):
    """A step of length h in STEP_SQRT_START equals SciPy's DOP853 step of size sqrt(h) on
    dy/ds = 2 s f(y) from s = 0 (t = t0 + s^2); STEP_SQRT_END equals its step of size
    -sqrt(h) on dy/ds = -2 s f(y) from s = sqrt(h) (t = t0 + h - s^2). To rounding (1e-20 m
    on displacements of 1e-5 m)."""
    u, v, cA, cg, load, inv_m, drag = _random_chain()
    n, m = 11, u.size
    h = 1.5e-6

    def acc(uu, vv):
        out = np.zeros(m)
        kernel.accelerations(uu, vv, cA, cg, kernel.LAW_LINEAR, load, inv_m, drag, out)
        return out

    a0 = acc(u, v)
    u1, v1 = np.zeros(m), np.zeros(m)
    dop853_step.rk_step(u, v, a0, h, mode, cA, cg, False, load, inv_m, drag,
                         np.zeros((dop853_step.N_STAGES, m)), np.zeros(m), np.zeros(m), u1, v1)
    sign = 1.0 if mode == dop853_step.STEP_SQRT_START else -1.0

    def rhs(s, y):
        uu, vv = np.zeros(m), np.zeros(m)
        uu[:n], vv[:n] = y[:n], y[n:]
        return sign * 2.0 * s * np.concatenate([y[n:], acc(uu, vv)[:n]])

    s0 = 0.0 if sign > 0 else np.sqrt(h)
    y0 = np.concatenate([u[:n], v[:n]])
    K = np.empty((dop.N_STAGES + 1, 2 * n))
    y1, _ = scipy_rk_step(rhs, s0, y0, rhs(s0, y0), sign * np.sqrt(h),
                          dop.A[:dop.N_STAGES, :dop.N_STAGES], dop.B, dop.C[:dop.N_STAGES], K)
    np.testing.assert_allclose(u1[:n] - u[:n], y1[:n] - u[:n], rtol=1e-11, atol=1e-20)
    np.testing.assert_allclose(v1[:n], y1[n:], rtol=1e-11, atol=1e-18)


def test_sqrt_step_keeps_the_order_at_a_closing():
    """The first step after a sphere touches a wall, its velocity against a reference of 64
    substeps (equal in s): in s = sqrt(t - t0) the error falls like h^6 (measured slope 6.2),
    as a regular step it falls like h^{5/2}, the velocity's Hertz term t^{5/2} (measured 2.4).
    Asserted: >= 5.5 and <= 3."""
    m = kernel.padded_length(1) + 1
    cA, cg, load, inv_m, drag = (np.zeros(m - 1) for _ in range(5))
    cA[0], inv_m[0] = 7.1e9, 1.0 / 0.45e-3

    def step(mode, h, u0=0.0, v0=0.3):
        u, v, a0 = np.zeros(m), np.zeros(m), np.zeros(m)
        u[0], v[0] = u0, v0
        kernel.accelerations(u, v, cA, cg, kernel.LAW_LINEAR, load, inv_m, drag, a0)
        u1, v1 = np.zeros(m), np.zeros(m)
        dop853_step.rk_step(u, v, a0, h, mode, cA, cg, False, load, inv_m, drag,
                             np.zeros((dop853_step.N_STAGES, m)), np.zeros(m), np.zeros(m),
                             u1, v1)
        return u1[0], v1[0]

    def reference(h):
        # 64 START substeps of equal length in s (the first from the contact, in s).
        ds = np.sqrt(h) / 64
        u, v = step(dop853_step.STEP_SQRT_START, ds**2)
        for i in range(1, 64):
            t_a, t_b = (i * ds) ** 2, ((i + 1) * ds) ** 2
            u, v = step(dop853_step.STEP_REGULAR, t_b - t_a, u, v)
        return v

    hs = np.array([4e-6, 2e-6, 1e-6])  # t_c = 31 us: h from t_c/8 to t_c/31
    ref = [reference(h) for h in hs]
    slopes = []
    for mode in (dop853_step.STEP_SQRT_START, dop853_step.STEP_REGULAR):
        errs = [abs(step(mode, h)[1] - r) for h, r in zip(hs, ref, strict=True)]
        slopes.append(np.polyfit(np.log(hs), np.log(errs), 1)[0])
    assert slopes[0] >= 5.5 and slopes[1] <= 3.0, slopes


def test_the_kernel_rounds_the_same_whatever_the_compiler_inlined():
    """Fused multiply-adds ("contract") and reassociation change results with the code LLVM
    inlines around them, and so with the order in which a process compiles the kernel's
    variants (a batch then differed from its single runs by 1e-13 after some test orders).
    The kernel's fast-math flags allow neither; every function it compiles uses them."""
    assert not {"contract", "reassoc", "fast"} & set(dop853_codegen.FASTMATH)
    assert dop853_step.FASTMATH == set(dop853_codegen.FASTMATH) == kernel.forces.FM
