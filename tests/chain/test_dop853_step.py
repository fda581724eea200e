"""The generated, unrolled DOP853 step against its generator and against SciPy's own step."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate._ivp import dop853_coefficients as dop
from scipy.integrate._ivp.rk import rk_step as scipy_rk_step

from msens.chain import _dop853_step, dop853_codegen, kernel


def test_committed_module_is_the_generator_output():
    assert dop853_codegen.TARGET.read_text() == dop853_codegen.step_source()


@pytest.mark.parametrize("law", [kernel.LAW_LINEAR, kernel.LAW_HKK])
def test_step_matches_scipy_dop853_step(law):
    """One step of the padded second-order form equals SciPy's DOP853 step on the first-order
    system (u, v)' = (v, a(u, v)) to rounding (measured: 6e-14 relative on the displacement
    increments, 4e-15 on the velocities)."""
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
    cA, cg, load_p, inv_m = (np.zeros(p) for _ in range(4))
    cA[:n], cg[:n], load_p[:n], inv_m[:n] = A, gam, load, 1.0 / mass
    Fp = np.zeros(p + 1)

    def acc(uu, vv):
        out = np.zeros(p + 1)
        kernel.accelerations(uu, vv, cA, cg, law, load_p, inv_m, Fp, out)
        return out

    a0 = acc(u, v)
    h = 1.5e-6
    kv = np.zeros((_dop853_step.N_STAGES, p + 1))
    u1, v1 = pad.copy(), pad.copy()
    _dop853_step.rk_step(u, v, a0, h, cA, cg, law == kernel.LAW_HKK, load_p, inv_m, kv,
                         pad.copy(), pad.copy(), Fp, u1, v1)

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
