"""The DAQ read-out's first-order-hold step: its per-process memo and its exactness."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import linalg

from msens.readout.daq import _foh_matrices, _foh_step
from msens.readout.electronics import ReadoutCircuit, state_space

#: The paper's coil on 1 m RG-58 into 1 MΩ ∥ 20 pF (as in test_electronics.py), with and
#: without the cable's series resistance.
CIRCUITS = (ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 1e6, 20e-12),
            ReadoutCircuit(92.0, 23e-3, 10.8e-12, 100e-12, 1e6, 20e-12,
                           cable_resistance=50.0))


def direct_foh(a: np.ndarray, b: np.ndarray, tau: float):
    """The step without any memo: Van Loan's block exponential, as the read-out builds it."""
    n, m = b.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = a
    big[:n, n:n + m] = b
    big[n:n + m, n + m:] = np.eye(m)
    e = linalg.expm(big * tau)
    return e[:n, :n], e[:n, n:n + m], e[:n, n + m:]


@pytest.mark.parametrize("circuit", CIRCUITS)
@pytest.mark.parametrize("tau", [1e-7, 0.37e-7, 2.5e-8])
def test_memo_returns_the_direct_computation_bit_for_bit(circuit, tau):
    a, b, _ = state_space(circuit)
    b_emf = b[:, :1]                                 # the EMF column, as daq_voltage passes it
    first = _foh_matrices(a, b_emf, tau)
    again = _foh_matrices(a.copy(), np.array(b_emf), tau)    # equal values, other arrays
    for got, hit, want in zip(first, again, direct_foh(a, b_emf, tau), strict=True):
        assert got.shape == want.shape
        assert np.array_equal(got, want)
        assert hit is got                            # the second call is served by the memo


def test_memo_keys_on_the_values_of_a_b_and_tau():
    a, b, _ = state_space(CIRCUITS[0])
    b_emf = b[:, :1]
    phi = _foh_matrices(a, b_emf, 1e-7)[0]
    assert np.array_equal(_foh_matrices(a, b_emf, 2e-7)[0], direct_foh(a, b_emf, 2e-7)[0])
    other = a.copy()
    other[0, 0] *= 1.5
    assert np.array_equal(_foh_matrices(other, b_emf, 1e-7)[0],
                          direct_foh(other, b_emf, 1e-7)[0])
    assert not np.array_equal(_foh_matrices(other, b_emf, 1e-7)[0], phi)
    a2, b2, _ = state_space(CIRCUITS[1])             # a different circuit (3 states, not 2)
    got = _foh_matrices(a2, b2[:, :1], 1e-7)
    assert got[0].shape == a2.shape
    assert np.array_equal(got[1], direct_foh(a2, b2[:, :1], 1e-7)[1])


def test_returned_arrays_are_read_only_and_the_memo_stays_intact():
    a0, b, _ = state_space(CIRCUITS[0])
    a, b_emf, tau = a0.copy(), b[:, :1], 0.61e-7
    arrays = _foh_matrices(a, b_emf, tau)
    for arr in arrays:
        assert not arr.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            arr[0, 0] = 1.0
    a[0, 0] = 0.0                  # the caller's input changing afterwards leaves the entry
    for got, want in zip(_foh_matrices(a0, b_emf, tau), direct_foh(a0, b_emf, tau),
                         strict=True):
        assert np.array_equal(got, want)
    assert not np.array_equal(_foh_matrices(a, b_emf, tau)[0], arrays[0])


def test_memo_is_bounded():
    a, b, _ = state_space(CIRCUITS[0])
    for k in range(_foh_step.cache_info().maxsize + 5):
        _foh_matrices(a, b[:, :1], (1.0 + k / 1000.0) * 1e-8)
    info = _foh_step.cache_info()
    assert info.currsize == info.maxsize


def test_step_is_exact_for_a_first_order_lag():
    """ẋ = -x/T + u/T: Φ = e^{-τ/T}, G0 = 1 - Φ, G1 = τ - T (1 - Φ), in closed form."""
    lag, tau = 2e-6, 0.7e-6
    phi, g0, g1 = _foh_matrices(np.array([[-1.0 / lag]]), np.array([[1.0 / lag]]), tau)
    decay = math.exp(-tau / lag)
    assert phi[0, 0] == pytest.approx(decay, rel=1e-13)
    assert g0[0, 0] == pytest.approx(1.0 - decay, rel=1e-12)
    assert g1[0, 0] == pytest.approx(tau - lag * (1.0 - decay), rel=1e-10)
