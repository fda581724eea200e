"""Sparse assembly with a cached pattern, Dirichlet condensation and the direct solver.

skfem's generic assembler rebuilds the COO → CSR conversion on every call; the Newton loop
assembles many matrices on one mesh, so the pattern (and its restriction to the free dofs) is
computed once and each assembly is a single ``np.bincount``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu


@dataclass(frozen=True)
class Pattern:
    """CSR pattern of a P-k stiffness matrix and of its free–free block.

    Attributes
    ----------
    n : int
        Number of dofs.
    slot : ndarray, shape (n_elements * n_bfun**2,)
        CSR data position of each element-matrix entry (row-major per element).
    indptr, indices : ndarray
        Full CSR structure.
    free : ndarray
        Free (non-Dirichlet) dofs, sorted.
    ff_pos : ndarray
        Positions in the full data array of the free–free entries.
    ff_indptr, ff_indices : ndarray
        CSR structure of the free–free block (free dofs renumbered 0..len(free)-1).
    """

    n: int
    slot: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    free: np.ndarray
    ff_pos: np.ndarray
    ff_indptr: np.ndarray
    ff_indices: np.ndarray


def build_pattern(element_dofs: np.ndarray, n: int, fixed: np.ndarray) -> Pattern:
    """Pattern for element dofs (shape (n_bfun, n_elements)) with ``fixed`` Dirichlet dofs."""
    dofs = element_dofs.T.astype(np.int64)
    nb = dofs.shape[1]
    rows = np.repeat(dofs, nb, axis=1).ravel()
    cols = np.tile(dofs, (1, nb)).ravel()
    # scipy's COO → CSR conversion (counting sort by row, then per-row column sort) gives
    # the canonical structure faster than np.unique over all row*n + col keys; the CSR keys
    # are then sorted, so each entry's slot is one searchsorted
    m = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    m.sum_duplicates()
    indptr = m.indptr.astype(np.int64)
    r = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    c = m.indices.astype(np.int64)
    slot = np.searchsorted(r * n + c, rows * n + cols)
    is_free = np.ones(n, dtype=bool)
    is_free[fixed] = False
    free = np.flatnonzero(is_free)
    g2f = -np.ones(n, dtype=np.int64)
    g2f[free] = np.arange(free.size)
    ff = is_free[r] & is_free[c]
    ff_pos = np.flatnonzero(ff)
    fr = g2f[r[ff]]
    ff_indptr = np.concatenate([[0], np.cumsum(np.bincount(fr, minlength=free.size))])
    return Pattern(n=n, slot=slot.ravel(), indptr=indptr, indices=c.astype(np.int32),
                   free=free, ff_pos=ff_pos, ff_indptr=ff_indptr,
                   ff_indices=g2f[c[ff]].astype(np.int32))


def assemble_matrix(pat: Pattern, ke: np.ndarray) -> tuple[sp.csr_matrix, sp.csc_matrix]:
    """Full matrix (CSR) and its free–free block (CSC) from element matrices.

    Parameters
    ----------
    ke : ndarray, shape (n_elements, n_bfun, n_bfun)
        Symmetric element matrices.
    """
    data = np.bincount(pat.slot, weights=ke.ravel(), minlength=pat.indices.size)
    full = sp.csr_matrix((data, pat.indices, pat.indptr), shape=(pat.n, pat.n))
    nf = pat.free.size
    # the block is symmetric, so its CSR arrays are also its CSC arrays
    ff = sp.csc_matrix((data[pat.ff_pos], pat.ff_indices, pat.ff_indptr), shape=(nf, nf))
    return full, ff


def assemble_vector(element_dofs: np.ndarray, fe: np.ndarray, n: int) -> np.ndarray:
    """Global vector from element vectors ``fe`` (shape (n_elements, n_bfun))."""
    return np.bincount(element_dofs.T.ravel(), weights=fe.ravel(), minlength=n)


def factorize(k_ff: sp.csc_matrix):
    """Sparse LU of a symmetric positive definite matrix (SuperLU, no pivoting).

    The minimum-degree ordering of Aᵀ + A suits symmetric matrices; with the diagonal pivot
    threshold at 0 SuperLU keeps that ordering (an SPD matrix needs no pivoting). A panel of 4
    columns instead of SuperLU's default 10 cut the factor time by ~10-20 % on the 103k-dof
    P2 benchmark (benchmarks/field_speed.py); fill is unchanged (ordering and supernodes
    are the same), and geometric nested dissection gave ~45 % more fill than MMD there.
    The supernode relaxation is kept at most the panel size, as in SuperLU's own defaults.
    """
    return splu(k_ff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, panel_size=4,
                relax=4, options={"SymmetricMode": True})
