"""The voltage the DAQ records: the read-out circuit's response to an EMF record, sampled.

Sampling: the DAQ is an ideal sampler at ``sample_rate`` — no anti-alias filter beyond the
circuit itself and the DAQ's input capacitance, which is how a wide-band digitiser running at
10 MHz behaves for a signal band of ~100 kHz. The EMF record is read as piecewise linear
between its samples (first-order hold) and the circuit's response to it is computed exactly
(matrix exponential) at the DAQ's sampling instants; noise (:mod:`msens.readout.noise`) is an
exact sampled realisation of the continuous-time process, so its aliasing is included.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike
from scipy import linalg

from msens.errors import require
from msens.readout.electronics import ReadoutCircuit, _linear_recursion, state_space
from msens.readout.noise import NoiseModel, add_readout_noise

#: Distinct (A, B, τ) first-order-hold steps kept per process by :func:`_foh_matrices`.
_FOH_MEMO_SIZE = 64


def _foh_matrices(a: np.ndarray, b: np.ndarray, tau: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact step of ẋ = Ax + Bu over τ with u(t) = u0 + t·du (first-order hold), memoised.

    A diagnosis or a sweep evaluates the same read-out circuit on the same EMF grid thousands
    of times: A and B depend only on the circuit and τ only on the EMF step and the DAQ
    sampling phase, so the matrix exponential behind each step is the same every time. The
    step is therefore computed once per distinct (A, B, τ) and kept in a small per-process
    memo (the ``_FOH_MEMO_SIZE`` most recently used; keyed by the exact bytes of A and B
    and the exact value of τ, so a hit returns exactly what a fresh computation would). The
    returned arrays are shared between callers and read-only: write into a copy.

    Parameters
    ----------
    a : ndarray, shape (n, n)
        State matrix A, 1/s.
    b : ndarray, shape (n, m)
        Input matrix B (state units per input unit per second).
    tau : float
        Step, s.

    Returns
    -------
    phi : ndarray, shape (n, n)
        Φ = exp(Aτ), dimensionless.
    g0 : ndarray, shape (n, m)
        Response to a constant input u0 over the step (state units per input unit).
    g1 : ndarray, shape (n, m)
        Response to an input slope du over the step (state units per input unit per 1/s).
        With these, x(τ) = Φ x(0) + G0 u0 + G1 du. All three are read-only.
    """
    a = np.ascontiguousarray(a, dtype=float)
    b = np.ascontiguousarray(b, dtype=float)
    return _foh_step(a.shape, b.shape, a.tobytes(), b.tobytes(), float(tau))


@functools.lru_cache(maxsize=_FOH_MEMO_SIZE)
def _foh_step(a_shape: tuple[int, int], b_shape: tuple[int, int], a_bytes: bytes,
              b_bytes: bytes, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Uncached first-order-hold step of :func:`_foh_matrices` from a hashable key."""
    n, m = b_shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = np.frombuffer(a_bytes, dtype=float).reshape(a_shape)
    big[:n, n:n + m] = np.frombuffer(b_bytes, dtype=float).reshape(b_shape)
    big[n:n + m, n + m:] = np.eye(m)
    e = linalg.expm(big * tau)
    e.flags.writeable = False                      # the views below share this memory
    return e[:n, :n], e[:n, n:n + m], e[:n, n + m:]


def daq_voltage(circuit: ReadoutCircuit, t: ArrayLike, emf: ArrayLike, sample_rate: float,
                *, noise: NoiseModel | None = None,
                rng: np.random.Generator | int | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
    """Voltage the DAQ records for an EMF record.

    The EMF is taken as piecewise linear between its samples; before ``t[0]`` it is held at
    ``emf[0]`` with the circuit in DC steady state. The response is computed exactly
    (first-order-hold matrix exponentials) on the EMF grid and, by partial steps, at the
    DAQ instants ``t[0] + k / sample_rate`` (k = 0, 1, … while ≤ t[-1]): an ideal sampler,
    no anti-alias filter beyond the circuit (module notes).

    Noise (if ``noise`` is given): an exact sampled realisation of the circuit-shaped
    Johnson noise of R, R_c and R_in; white DAQ input noise of variance e_n² fs/2 per
    sample; then ADC quantisation and clipping.

    Parameters
    ----------
    circuit : ReadoutCircuit
    t : array_like, shape (n,)
        Uniformly spaced times of the EMF record, s (n >= 2).
    emf : array_like, shape (n,)
        Induced EMF, V.
    sample_rate : float
        DAQ sampling rate, Hz (paper: 10 MHz).
    noise : NoiseModel, optional
    rng : numpy.random.Generator or int, optional
        Generator or seed for the noise; None = seed 0 (reproducible by default: pass
        different seeds for independent realisations).

    Returns
    -------
    t_daq : ndarray, shape (m,)
        Sampling instants, s.
    v_daq : ndarray, shape (m,)
        Voltage at the DAQ, V.
    """
    t = np.asarray(t, dtype=float)
    emf = np.asarray(emf, dtype=float)
    require(t.ndim == 1 and t.shape == emf.shape and t.size >= 2,
            f"t and emf must be 1-D arrays of equal length >= 2, got shapes {t.shape} and "
            f"{emf.shape}")
    require(bool(np.all(np.isfinite(t)) and np.all(np.isfinite(emf))),
            "t and emf must be finite")
    dt = (t[-1] - t[0]) / (t.size - 1)
    require(dt > 0 and bool(np.allclose(np.diff(t), dt, rtol=1e-6, atol=0.0)),
            "EMF times t must be increasing and uniformly spaced")
    require(math.isfinite(sample_rate) and sample_rate > 0,
            f"sample_rate must be > 0 Hz, got {sample_rate}")

    a, b, c = state_space(circuit)
    b_emf = b[:, :1]
    slope = np.diff(emf) / dt
    phi, g0, g1 = _foh_matrices(a, b_emf, dt)
    drive = np.outer(emf[:-1], g0[:, 0]) + np.outer(slope, g1[:, 0])
    x0 = -linalg.solve(a, b_emf[:, 0] * emf[0])
    x = _linear_recursion(phi, x0, np.ascontiguousarray(drive))

    n_daq = math.floor((t[-1] - t[0]) * sample_rate * (1 + 1e-12)) + 1
    t_daq = t[0] + np.arange(n_daq) / sample_rate
    pos = (t_daq - t[0]) / dt
    j = np.minimum(np.floor(pos + 1e-9).astype(int), t.size - 2)
    frac = np.clip(pos - j, 0.0, 1.0)
    key = np.round(frac * 1e9).astype(np.int64)    # partial steps equal to 1e-9 dt share Φ
    v = np.empty(n_daq)
    for k in np.unique(key):
        sel = key == k
        jj = j[sel]
        if k == 0:
            v[sel] = x[jj] @ c
            continue
        p_tau, h0, h1 = _foh_matrices(a, b_emf, frac[sel][0] * dt)
        xs = x[jj] @ p_tau.T + np.outer(emf[jj], h0[:, 0]) + np.outer(slope[jj], h1[:, 0])
        v[sel] = xs @ c

    if noise is not None:
        v = add_readout_noise(v, circuit, noise, sample_rate, rng=rng)
    return t_daq, v
