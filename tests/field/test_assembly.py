"""Cached sparsity pattern and the direct solver against scipy's generic sparse tools."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import skfem
from scipy.sparse.linalg import spsolve

from msens.field.assembly import assemble_matrix, build_pattern
from msens.field.forms import element_stiffness, quadrature_data
from msens.field.linsolve import factorize


def _basis(order: int) -> skfem.CellBasis:
    mesh = skfem.MeshTri.init_tensor(np.linspace(0.0, 1.0, 7), np.linspace(-0.5, 0.5, 6))
    # seeded jitter of the interior nodes: an irregular but valid triangulation
    rng = np.random.default_rng(7)
    p = mesh.p.copy()
    inner = np.flatnonzero(~np.isin(np.arange(p.shape[1]), mesh.boundary_nodes()))
    p[:, inner] += rng.uniform(-0.02, 0.02, (2, inner.size))
    elem = skfem.ElementTriP2() if order == 2 else skfem.ElementTriP1()
    return skfem.CellBasis(skfem.MeshTri(p, mesh.t), elem, intorder=2 * order)


def _reference(basis: skfem.CellBasis, ke: np.ndarray) -> sp.csr_matrix:
    """COO → CSR with duplicates summed: scipy's canonical assembly of the element matrices."""
    dofs = basis.element_dofs.T
    nb = dofs.shape[1]
    rows = np.repeat(dofs, nb, axis=1).ravel()
    cols = np.tile(dofs, (1, nb)).ravel()
    m = sp.csr_matrix((ke.ravel(), (rows, cols)), shape=(basis.N, basis.N))
    m.sum_duplicates()
    return m


@pytest.mark.parametrize("order", [1, 2])
def test_pattern_matches_scipy_assembly(order):
    basis = _basis(order)
    q = quadrature_data(basis)
    rng = np.random.default_rng(3)
    # element matrices with distinct random entries, so any wrong slot shows up
    ke = rng.standard_normal((basis.mesh.t.shape[1], basis.Nbfun, basis.Nbfun))
    fixed = np.unique(basis.get_dofs(basis.mesh.boundary_facets()).flatten())
    pat = build_pattern(basis.element_dofs, basis.N, fixed)
    full, _ = assemble_matrix(pat, ke)
    ref = _reference(basis, ke)
    # same canonical structure (sorted columns) and the same sums up to summation order
    np.testing.assert_array_equal(full.indptr, ref.indptr)
    np.testing.assert_array_equal(full.indices, ref.indices)
    np.testing.assert_allclose(full.data, ref.data, rtol=0, atol=1e-13)
    # free–free block: its CSC arrays are the CSR arrays of the restricted full matrix (the
    # same matrix when symmetric, i.e. it is exactly the transpose of the restriction)
    ks = element_stiffness(q, np.ones(q.w.shape))
    full_s, ff = assemble_matrix(pat, ks)
    np.testing.assert_array_equal(pat.free, np.setdiff1d(np.arange(basis.N), fixed))
    sub = full_s[pat.free][:, pat.free]
    sub.sort_indices()
    assert abs(sub - sub.T).max() <= 1e-12 * abs(sub).max()
    np.testing.assert_array_equal(ff.indptr, sub.indptr)
    np.testing.assert_array_equal(ff.indices, sub.indices)
    np.testing.assert_array_equal(ff.data, sub.data)


def test_pattern_without_fixed_dofs_is_the_full_matrix():
    basis = _basis(2)
    q = quadrature_data(basis)
    pat = build_pattern(basis.element_dofs, basis.N, np.array([], dtype=np.int64))
    full, ff = assemble_matrix(pat, element_stiffness(q, np.ones(q.w.shape)))
    assert pat.free.size == basis.N
    assert abs(full - ff.T).max() == 0.0


def test_factorize_solves_vectors_and_blocks_repeatedly():
    basis = _basis(2)
    q = quadrature_data(basis)
    fixed = np.unique(basis.get_dofs(basis.mesh.boundary_facets()).flatten())
    pat = build_pattern(basis.element_dofs, basis.N, fixed)
    _, ff = assemble_matrix(pat, element_stiffness(q, 1.0 + q.r))
    rng = np.random.default_rng(11)
    b = rng.standard_normal((pat.free.size, 3))
    lu = factorize(ff)
    x_block = lu.solve(b)
    assert x_block.shape == b.shape
    for k in range(3):
        ref = spsolve(ff, b[:, k])
        # the factor is reused: each column solve must match the block solve
        np.testing.assert_allclose(lu.solve(b[:, k]), ref, rtol=1e-10, atol=0)
        np.testing.assert_allclose(x_block[:, k], ref, rtol=1e-10, atol=0)
