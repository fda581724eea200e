"""Tables stored as truncated decompositions: what lets the main study's coil tables ship.

A coil's tables (:mod:`msens.magnetics.coil_read`, :mod:`msens.magnetics.eddy_coil_read`)
hold many smooth, alike functions over one grid: every source's flux over the coil's window,
at every frequency, and the window's cell-to-cell inductance kernel. Stacked as a matrix they
are nearly of low rank, so a truncated decomposition stores them in a few MB instead of tens:

- :func:`rows_svd`: any real or complex matrix, each row scaled to unit 2-norm first (a weak
  row keeps the relative accuracy of the strongest), then a truncated SVD;
- :func:`symmetric_eig`: a symmetric matrix (the inductance kernel K = P K_t⁻¹ Pᵀ) as its
  leading eigenpairs, half the storage of an SVD.

Both keep the singular values (|eigenvalues|) above ``rank_tol`` times the largest; the
second factor is stored in single precision (about 1e-7 of the largest entry).
"""

from __future__ import annotations

import numpy as np


def rows_svd(matrix: np.ndarray, rank_tol: float) -> tuple[np.ndarray, np.ndarray]:
    """``matrix`` ≈ u @ v, truncated to the singular values above ``rank_tol`` × the
    largest of its row-normalised form.

    Parameters
    ----------
    matrix : ndarray, shape (m, n)
        Real or complex.
    rank_tol : float
        Relative singular-value threshold.

    Returns
    -------
    u : ndarray, shape (m, k)
        U_k Σ_k with the row scales put back (the matrix's precision).
    v : ndarray, shape (k, n)
        V_kᴴ in single precision (complex64 or float32).
    """
    m = np.asarray(matrix)
    w = np.linalg.norm(m, axis=1)
    w = np.where(w > 0.0, w, 1.0)
    u, s, vh = np.linalg.svd(m / w[:, None], full_matrices=False)
    k = max(int(np.sum(s > rank_tol * s[0])), 1)
    single = np.complex64 if np.iscomplexobj(m) else np.float32
    return w[:, None] * u[:, :k] * s[:k], vh[:k].astype(single)


def symmetric_eig(matrix: np.ndarray, rank_tol: float) -> tuple[np.ndarray, np.ndarray]:
    """A real symmetric ``matrix`` ≈ q @ diag(lam) @ qᵀ, keeping the eigenvalues with
    |λ| above ``rank_tol`` × the largest |λ|.

    Returns
    -------
    q : ndarray, shape (n, k)
        Eigenvectors, float32.
    lam : ndarray, shape (k,)
        Eigenvalues, float64.
    """
    m = np.asarray(matrix, dtype=float)
    lam, q = np.linalg.eigh((m + m.T) / 2)
    keep = np.abs(lam) > rank_tol * np.max(np.abs(lam))
    if not np.any(keep):
        keep[np.argmax(np.abs(lam))] = True
    return q[:, keep].astype(np.float32), lam[keep]


def expand_symmetric(q: np.ndarray, lam: np.ndarray, dtype=np.float32) -> np.ndarray:
    """The matrix :func:`symmetric_eig` factored, shape (n, n), in ``dtype``."""
    q = np.asarray(q, dtype=float)
    return ((q * lam) @ q.T).astype(dtype)


__all__ = ["expand_symmetric", "rows_svd", "symmetric_eig"]
