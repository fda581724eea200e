"""Compiled fixed-step integrator against SciPy's adaptive DOP853 on the paper chain."""

import numpy as np
import pytest

from msens.chain import DampingLaw, paper_chain, simulate, simulate_reference, striker_velocity

T = np.linspace(0.0, 1e-3, 2001)


@pytest.mark.parametrize("law, gamma, tol", [
    # measured peak errors at the default step: 4.0e-8, 3.5e-8, 1.9e-7
    (DampingLaw.LINEAR, 4.8, 1e-6),
    (DampingLaw.LINEAR_LOADING, 4.8, 1e-6),
    (DampingLaw.HERTZ_KUWABARA_KONO, 4.8e3, 2e-6),
])
def test_peak_forces_agree_with_adaptive_reference(law, gamma, tol):
    chain = paper_chain(gamma, damping_law=law)
    v = striker_velocity()
    fast = simulate(chain, v, T)
    ref = simulate_reference(chain, v, T, rtol=1e-11)
    peak, peak_ref = fast.force.max(axis=0), ref.force.max(axis=0)
    assert np.max(np.abs(peak / peak_ref - 1.0)) < tol
    # whole waveforms (t > 0: at t = 0 the reference sees delta = 0, i.e. no dashpot yet)
    assert np.max(np.abs(fast.force[1:] - ref.force[1:])) < 20 * tol * peak_ref.max()
