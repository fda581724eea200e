"""Contact forces, accelerations and jerks of the chain on the kernel's padded layout.

Padded layout: ``p`` >= n is n rounded up to a multiple of ``PAD`` (:func:`padded_length`);
particle arrays have shape (p + 1,) with zeros from entry n on (entry n is the wall), so
contact k is always between entries k and k + 1, the wall contact needs no special case and
every loop runs over p entries, vectorised without a scalar remainder. Contact arrays have
shape (p,), zero past n. The contact states enter as the products ``cA`` = closed * A and
``cg`` = dashpot-on * gamma, so that the force loops have no branches.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from msens.chain.kernel.dop853_step import FASTMATH
from msens.chain.kernel.noalias import njit_noalias

#: Force-law codes of the kernel (see :class:`msens.chain.model.DampingLaw`).
LAW_LINEAR = 0
LAW_HKK = 1
LAW_LINEAR_LOADING = 2
#: State arrays are padded to a multiple of this length (8 doubles = one AVX-512 register).
PAD = 8
#: Fast-math flags of the vectorised passes (those of the generated Runge-Kutta step).
FM = set(FASTMATH)


@nb.njit(cache=True)
def padded_length(n: int) -> int:
    """Row length p of the output arrays for n particles: n rounded up to a multiple of 8."""
    return -(-n // PAD) * PAD


@nb.njit(cache=True)
def zeros64(size):
    """Zeros of shape (size,) starting on a 64-byte boundary (a cache line, one AVX-512
    register). numba aligns arrays to 32 bytes only, so whether the scratch arrays' full-width
    loads straddle cache lines would vary with the heap's state, and the run time with it;
    aligned, the layout is the same in every run."""
    buf = np.zeros(size + 8)
    off = (-(buf.ctypes.data // 8)) % 8
    return buf[off:off + size]


@nb.njit(cache=True)
def zeros64_rows(rows, cols):
    """Zeros of shape (rows, c), c = cols rounded up to a multiple of 8, so that every row
    starts on a 64-byte boundary (C-contiguous; the columns past cols are spare)."""
    stride = padded_length(cols)
    return zeros64(rows * stride).reshape((rows, stride))


@nb.njit(cache=True, inline="always")
def force(g, r, cA, cg, hkk):
    # Force of a contact (coefficients cA = closed * A, cg = dashpot * gamma) from its gap g
    # and gap rate r, written as in the generated Runge-Kutta step. (The loop-invariant law
    # test is hoisted: loop unswitching.)
    dp = max(g, 0.0)
    w = np.sqrt(dp)
    return cA * dp * w + cg * r * (w if hkk else 1.0)


@njit_noalias(cache=True, fastmath=FM)
def contact_forces(u, v, cA, cg, law, Fp):
    """Contact forces (N) on the padded layout, shifted by one into ``Fp``.

    Padded layout: ``p`` >= n is n rounded up to a multiple of ``PAD`` and ``u``, ``v``
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
        Fp[k + 1] = force(u[k] - u[k + 1], v[k] - v[k + 1], cA[k], cg[k], hkk)


@njit_noalias(cache=True, fastmath=FM)
def accelerations(u, v, cA, cg, law, load, inv_m, drag, out):
    """Accelerations (m/s^2) into ``out`` (p + 1,) on the padded layout (zero past n).

    ``load``, ``inv_m`` and ``drag`` (each particle's viscous drag coefficient over its
    mass, c/m in 1/s: the drag on the tube adds -c v / m) are padded with zeros to (p,).
    Forces and the particle balance in one branch-free pass, as in the generated
    Runge-Kutta step: the force of the contact above particle k is carried over from the
    previous iteration.
    """
    n = cA.shape[0]
    hkk = law == LAW_HKK
    f_prev = 0.0
    for k in range(n):
        f = force(u[k] - u[k + 1], v[k] - v[k + 1], cA[k], cg[k], hkk)
        out[k] = (load[k] + f_prev - f) * inv_m[k] - drag[k] * v[k]
        f_prev = f
    for i in range(n, u.shape[0]):
        out[i] = 0.0


@nb.njit(cache=True, inline="always")
def dforce(g, r, q, cA, cg):
    # dF/dt of a contact along the motion (linear-dashpot laws) from its gap g, gap rate r and
    # relative acceleration q (scalars, so that the calling loops vectorise).
    return 1.5 * cA * np.sqrt(max(g, 0.0)) * r + cg * q


@njit_noalias(cache=True, fastmath=FM)
def jerks(u, v, a, cA, cg, inv_m, drag, out):
    """Time derivatives of the accelerations (m/s^3) into ``out`` (p + 1,), linear-dashpot laws.

    Differentiates Eq. 6 along the motion: dF/dt = (3/2) A sqrt(delta) d(delta)/dt
    + gamma d^2(delta)/dt^2 with the relative acceleration from ``a``, and the drag term
    -(c/m) a (``drag`` = c/m as in :func:`accelerations`). Padded layout as in
    :func:`accelerations` (one pass). (Not for the Kuwabara-Kono law, whose dF/dt is
    unbounded where a contact opens or closes.)
    """
    n = cA.shape[0]
    d_prev = 0.0
    for k in range(n):
        d = dforce(u[k] - u[k + 1], v[k] - v[k + 1], a[k] - a[k + 1], cA[k], cg[k])
        out[k] = (d_prev - d) * inv_m[k] - drag[k] * a[k]
        d_prev = d
    for i in range(n, u.shape[0]):
        out[i] = 0.0


@nb.njit(cache=True, inline="always")
def gap(x, k):
    # Padded layout: x[n] is the wall, so the wall contact needs no special case.
    return x[k] - x[k + 1]
