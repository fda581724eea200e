"""Point evaluation of P2 fields on straight triangles: sparse probe matrices for many points
(linkage tables, moving a solution onto another mesh of the same domain)."""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.tri as mtri
import numpy as np
import scipy.sparse as sp

from msens.errors import internal


def p2_probes(basis, r: np.ndarray, z: np.ndarray, *, outside_zero: bool = False
              ) -> sp.csr_matrix:
    """Sparse evaluation matrix of a P2 field on straight triangles at points, (n_pts, N).

    Point location by matplotlib's trapezoid-map finder (fast for many points); P2 shape
    functions in barycentric coordinates λ: λ_i(2λ_i − 1) at the vertices, 4 λ_i λ_j on the
    edges (0,1), (1,2), (0,2) — scikit-fem's local dof order for ElementTriP2 (checked against
    ``basis.probes`` in the tests). Points outside the mesh are an error, or with
    ``outside_zero`` rows of zeros. ``basis``: a scikit-fem P2 basis, or a :class:`P2Field`
    (what is read of it: ``mesh``, ``element_dofs``, ``N``).
    """
    mesh = basis.mesh
    tri = mtri.Triangulation(mesh.p[0], mesh.p[1], mesh.t.T)
    e = tri.get_trifinder()(r, z)
    if outside_zero:
        inside = np.flatnonzero(e >= 0)
        m = p2_probes(basis, r[inside], z[inside])
        rows = np.repeat(inside, np.diff(m.indptr))
        return sp.csr_matrix((m.data, (rows, m.indices)), shape=(r.size, basis.N))
    internal(bool(np.all(e >= 0)), "internal: linkage-table points outside the field mesh")
    p0, p1, p2 = (mesh.p[:, mesh.t[k, e]] for k in range(3))
    det = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1])
    l1 = ((r - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (z - p0[1])) / det
    l2 = ((p1[0] - p0[0]) * (z - p0[1]) - (r - p0[0]) * (p1[1] - p0[1])) / det
    l0 = 1.0 - l1 - l2
    shape = np.stack([l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1),
                      4 * l0 * l1, 4 * l1 * l2, 4 * l0 * l2])
    rows = np.broadcast_to(np.arange(r.size), shape.shape)
    return sp.csr_matrix((shape.ravel(), (rows.ravel(), basis.element_dofs[:, e].ravel())),
                         shape=(r.size, basis.N))


@dataclass(frozen=True)
class P2Field:
    """A P2 field with just what :func:`p2_probes` needs: light to send to another process
    (a solution's basis holds every element's shape functions).

    Attributes
    ----------
    mesh : skfem.MeshTri
    element_dofs : ndarray of int, shape (6, n_elements)
        Global dof of each local basis function (scikit-fem's order).
    a : ndarray, shape (n_dofs,)
        The dofs.
    """

    mesh: object
    element_dofs: np.ndarray
    a: np.ndarray

    @classmethod
    def of(cls, solution) -> P2Field:
        """The field of a P2 :class:`msens.field.solve.FieldSolution`."""
        return cls(solution.basis.mesh, solution.basis.element_dofs, solution.a)

    @property
    def N(self) -> int:  # scikit-fem's name for the dof count
        """Number of dofs."""
        return int(self.a.size)

    def at(self, r: np.ndarray, z: np.ndarray, *, outside_zero: bool = False) -> np.ndarray:
        """The field at points (m, shape (n,) each), shape (n,) (:func:`p2_probes`)."""
        return p2_probes(self, r, z, outside_zero=outside_zero) @ self.a


__all__ = ["P2Field", "p2_probes"]
