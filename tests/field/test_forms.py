"""The vectorised kernels (msens.field.forms) against scikit-fem's own assembly."""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from msens.field.assembly import assemble_matrix, assemble_vector, build_pattern
from msens.field.forms import (
    axisym_load,
    axisym_stiffness,
    element_load,
    element_stiffness,
    quadrature_data,
)
from msens.field.verification_geometry import Part, build_mesh


@pytest.fixture(scope="module")
def basis():
    axi = build_mesh([Part("core", "rect", (0.0, 0.01, -0.01, 0.01), 3e-3)], 0.05, 0.02)
    return skfem.CellBasis(axi.mesh, skfem.ElementTriP2(), intorder=4)


def test_stiffness_kernel_equals_skfem_form(basis):
    rng = np.random.default_rng(1)
    nu = rng.uniform(1.0, 5.0, basis.nelems)[:, None] * np.ones((1, basis.X.shape[1]))
    ref = skfem.asm(axisym_stiffness, basis, nu=nu)
    pat = build_pattern(basis.element_dofs, basis.N, np.array([], dtype=np.int64))
    full, _ = assemble_matrix(pat, element_stiffness(quadrature_data(basis), nu))
    assert abs(full - ref).max() <= 1e-12 * abs(ref).max()


def test_tensor_kernel_with_isotropic_tensor_equals_scalar(basis):
    q = quadrature_data(basis)
    nu = np.full(q.w.shape, 3.0)
    tensor = nu[..., None, None] * np.eye(2)
    np.testing.assert_allclose(element_stiffness(q, tensor), element_stiffness(q, nu),
                               rtol=1e-13, atol=1e-13 * np.abs(element_stiffness(q, nu)).max())


def test_load_kernel_equals_skfem_form(basis):
    rng = np.random.default_rng(2)
    j, hc = rng.normal(size=basis.nelems), rng.normal(size=basis.nelems)
    shape = (basis.nelems, basis.X.shape[1])
    ref = skfem.asm(axisym_load, basis, j=np.repeat(j, shape[1]).reshape(shape),
                    hc=np.repeat(hc, shape[1]).reshape(shape))
    got = assemble_vector(basis.element_dofs, element_load(quadrature_data(basis), j, hc),
                          basis.N)
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_uniform_field_has_zero_energy_residual(basis):
    # A = B0 r/2 (uniform B_z = B0) is in the P2 space and divergence-free in air: K a = 0
    # at every dof away from the boundary.
    q = quadrature_data(basis)
    a = 0.7 * basis.doflocs[0] / 2
    pat = build_pattern(basis.element_dofs, basis.N, np.array([], dtype=np.int64))
    full, _ = assemble_matrix(pat, element_stiffness(q, np.ones(q.w.shape)))
    interior = np.setdiff1d(np.arange(basis.N), basis.get_dofs().flatten())
    assert np.abs((full @ a)[interior]).max() < 1e-12 * np.abs(full @ a).max()
