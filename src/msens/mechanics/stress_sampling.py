"""Reading a solved bead's stress (:class:`msens.mechanics.beadstress.BeadStress`).

:func:`stress_at` samples the stress at points of the meridian section, :func:`stress_along`
its component along a direction, :func:`mean_stress` the bead averages, and
:func:`mean_stress_exact` the closed form of the average (mean-stress theorem) they are
checked against.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import skfem
from scipy.integrate import quad
from skfem import Functional

from msens.errors import InputError, require
from msens.mechanics.beadstress import BeadStress
from msens.mechanics.elasticity import axisymmetric_stress, lame_parameters


def stress_at(bs: BeadStress, r: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Stress components at points of the bead (full sphere, centre at the origin).

    Parameters
    ----------
    bs : BeadStress
    r : array_like
        Radial coordinates, m, >= 0.
    z : array_like
        Axial coordinates, m (either hemisphere); broadcast with ``r``; r^2 + z^2 <= R^2.

    Returns
    -------
    ndarray, shape (*broadcast(r, z).shape, 4)
        (sigma_rr, sigma_zz, sigma_thth, sigma_rz), Pa, at force ``bs.force``.
        Compression is negative. The lower hemisphere follows by mirror symmetry
        (sigma_rz changes sign).
    """
    r, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(z, dtype=float))
    shape = r.shape
    r, z = r.ravel(), z.ravel()
    R = bs.radius
    if np.any(r < 0) or np.any(np.hypot(r, z) > R * (1 + 1e-9)):
        raise InputError(f"points must satisfy r >= 0 and r^2 + z^2 <= R^2 with R = {R:g} m")
    sign = np.where(z < 0, -1.0, 1.0)
    pts = np.vstack([r, np.abs(z) - R])  # mesh coordinates (r, s = z - R)
    cells, local = _locate(bs.stress_basis, pts)
    sb = bs.stress_basis
    phis = np.array([np.asarray(sb.elem.gbasis(sb.mapping, local, k, tind=cells)[0])
                     for k in range(sb.Nbfun)])[:, :, 0]  # (Nbfun, npts)
    vals = np.einsum("kp,ckp->pc", phis, bs.stress_dofs[:, sb.element_dofs[:, cells]])
    vals[:, 3] *= sign
    return vals.reshape(*shape, 4)


def _locate(basis: skfem.CellBasis, pts: np.ndarray, candidates: int = 12
            ) -> tuple[np.ndarray, np.ndarray]:
    """Element and reference coordinates of points in a (possibly curved) triangle mesh.

    skfem has no element finder for quadratic meshes, so each point is tried in the
    elements with the nearest centroids: Newton inverts the isoparametric map (without
    clipping, so points outside an element get coordinates outside the reference
    triangle), and the first element whose reference coordinates lie inside, up to a small
    tolerance that absorbs points on element edges and the arc, is taken.

    Parameters
    ----------
    basis : skfem.CellBasis
    pts : ndarray, shape (2, n)

    Returns
    -------
    cells : ndarray of int, shape (n,)
    local : ndarray, shape (2, n, 1)
        Reference coordinates, clipped onto the reference triangle.
    """
    from scipy.spatial import cKDTree

    mesh, mapping = basis.mesh, basis.mapping
    k = min(candidates, mesh.t.shape[1])
    centroids = mesh.p[:, mesh.t].mean(axis=1).T
    _, near = cKDTree(centroids).query(pts.T, k)  # (n, k)
    n = pts.shape[1]
    tind = near.T.ravel()  # candidate-major: all points for candidate 0, then 1, ...
    x = np.tile(pts, (1, k))[:, :, None]
    X = np.full((2, n * k, 1), 1.0 / 3.0)
    with np.errstate(all="ignore"):
        for _ in range(25):
            dX = np.einsum("ijkl,jkl->ikl", mapping.invDF(X, tind), x - mapping.F(X, tind))
            X = np.clip(X + dX, -2.0, 3.0)  # keep far-away candidates finite
    X = np.nan_to_num(X, nan=9.0).reshape(2, k, n)
    def within(tol):
        return (X[0] >= -tol) & (X[1] >= -tol) & (X[0] + X[1] <= 1 + tol)  # (k, n)

    # points between the quadratic boundary and the true arc (O(h^3) apart) need the
    # looser tolerance; interior points are found with the strict one
    inside = within(1e-8)
    loose = within(1e-2)
    inside = np.where(inside.any(axis=0), inside, loose)
    found = inside.any(axis=0)
    if not found.all():
        bad = pts[:, ~found][:, 0]
        raise InputError(f"point (r, z) = ({bad[0]:g}, {bad[1]:g}) m is not in the bead mesh")
    first = inside.argmax(axis=0)
    cells = near[np.arange(n), first]
    local = X[:, first, np.arange(n)]
    local = np.clip(local, 0.0, 1.0)
    over = local.sum(axis=0)
    local = np.where(over > 1.0, local / np.maximum(over, 1.0), local)
    return cells, local[:, :, None]


def mean_stress(bs: BeadStress) -> dict[str, float]:
    """Volume-averaged stress over the whole bead.

    Parameters
    ----------
    bs : BeadStress

    Returns
    -------
    dict of float
        Averages over the discrete bead volume, Pa:

        - ``"zz"``: <sigma_zz>; the mean-stress theorem gives -3 F / (2 pi R^2) (see
          :func:`mean_stress_exact` for the O(a^2/R^2) correction of the curved caps).
        - ``"xx"`` (= ``"yy"``): Cartesian transverse average (<sigma_rr> + <sigma_thth>)/2,
          zero by the mean-stress theorem since the tractions are axial.
        - ``"rr"``, ``"tt"``: averages of the cylindrical components. These are *not*
          zero separately (their sum is): the cylindrical basis rotates with the point.
        - ``"rz"``: <sigma_rz> over the whole sphere, 0 by mirror symmetry.
        - ``"volume"``: discrete bead volume, m^3.
    """
    lam, mu = lame_parameters(bs.youngs_modulus, bs.poisson_ratio)
    ui = bs.basis.interpolate(bs.displacement)

    def average(k):
        @Functional
        def integrand(w):
            return axisymmetric_stress(w.u, w.x[0], lam, mu)[k] * w.x[0]
        return float(integrand.assemble(bs.basis, u=ui))

    @Functional
    def volume(w):
        return w.x[0]

    v = float(volume.assemble(bs.basis))
    rr, zz, tt = (average(k) / v for k in range(3))
    return {"zz": zz, "xx": 0.5 * (rr + tt), "rr": rr, "tt": tt, "rz": 0.0,
            "volume": 4.0 * np.pi * v}


def mean_stress_exact(radius: float, force: float, contact_radius: float = 0.0) -> float:
    """Exact bead-average axial stress under two opposite axial Hertz loads, Pa.

    By the mean-stress theorem <sigma_zz> = (1/V) * (surface integral of z t_z). For
    point loads this is
    -2 F R / V = -3 F / (2 pi R^2). A Hertz pressure on a cap of radius a acts at
    z = sqrt(R^2 - rho^2) < R, which lowers the magnitude by about a^2 / (5 R^2).

    Parameters
    ----------
    radius : float
        R, m.
    force : float
        F, N.
    contact_radius : float, optional
        a, m; 0 for point loads.

    Returns
    -------
    float
        <sigma_zz>, Pa (negative: compression).
    """
    point = -3.0 * force / (2.0 * np.pi * radius**2)
    if contact_radius == 0.0:
        return point
    a2 = contact_radius**2
    # <z> over the Hertz distribution: with u = rho^2 the weight is sqrt(a^2 - u) du,
    # integrated exactly by QUADPACK's algebraic-endpoint rule
    num, _ = quad(lambda u: np.sqrt(radius**2 - u), 0.0, a2, weight="alg", wvar=(0.0, 0.5),
                  epsabs=0.0, epsrel=1e-13)
    mean_z = num / (2.0 / 3.0 * a2**1.5)
    return point * mean_z / radius


def stress_along(bs: BeadStress, r: np.ndarray, z: np.ndarray, direction: np.ndarray,
                 kind: Literal["normal", "deviatoric"] = "normal") -> np.ndarray:
    """Equivalent uniaxial stress along a direction field in the meridian plane.

    Parameters
    ----------
    bs : BeadStress
    r, z : array_like
        Points, m, broadcast together to shape S.
    direction : array_like, shape (*S, 2)
        (h_r, h_z) of the direction (e.g. the local bias field); normalised here;
        must be non-zero. An axisymmetric field has no hoop component.
    kind : {"normal", "deviatoric"}
        ``"normal"``: the normal stress h.sigma.h. ``"deviatoric"``: (3/2) h.s.h with
        s = sigma - tr(sigma)/3 I, the equivalent stress of Daniel & Hubert (2009,
        Eur. Phys. J. Appl. Phys. 45, 31101) for magnetoelastic coupling; it equals the
        applied stress for a uniaxial stress along h and ignores hydrostatic pressure.

    Returns
    -------
    ndarray, shape S
        Pa.
    """
    require(kind in ("normal", "deviatoric"),
            f"kind must be 'normal' or 'deviatoric', got {kind!r}")
    s = stress_at(bs, r, z)
    h = np.broadcast_to(np.asarray(direction, dtype=float), (*s.shape[:-1], 2))
    norm = np.hypot(h[..., 0], h[..., 1])
    require(bool(np.all(norm > 0)), "direction must be non-zero at every point")
    hr, hz = h[..., 0] / norm, h[..., 1] / norm
    s_rr, s_zz, s_tt, s_rz = (s[..., k] for k in range(4))
    normal = hr**2 * s_rr + hz**2 * s_zz + 2 * hr * hz * s_rz
    if kind == "normal":
        return normal
    return 1.5 * (normal - (s_rr + s_zz + s_tt) / 3.0)
