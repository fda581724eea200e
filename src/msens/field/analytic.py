"""Closed-form magnetostatic references used to verify the field solver.

Pure vectorised functions, SI units. Sources: the on-axis solenoid and magnet formulas are
Biot–Savart integrals of current loops; loop potential and mutual inductance from Smythe,
*Static and Dynamic Electricity* (1950) §7.10 and Grover, *Inductance Calculations* (1946);
the geometric mean distance of a rectangle from Maxwell, *Treatise* vol. 2 §691.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ellipe, ellipk

from msens.params.units import MU0


def thin_solenoid_bz(z: ArrayLike, radius: float, length: float, n_per_m: float,
                     current: float) -> np.ndarray:
    """On-axis B_z of a current sheet (radius R, length L, n turns/m, current I), T.

    B = (μ0 n I/2) [(z + L/2)/√(R² + (z + L/2)²) − (z − L/2)/√(R² + (z − L/2)²)].
    """
    z = np.asarray(z, dtype=float)
    u, v = z + length / 2, z - length / 2
    return 0.5 * MU0 * n_per_m * current * (u / np.hypot(radius, u) - v / np.hypot(radius, v))


def thick_solenoid_bz(z: ArrayLike, r1: float, r2: float, length: float,
                      current_density: float) -> np.ndarray:
    """On-axis B_z of a uniform azimuthal current density J in r1<=r<=r2, |z|<=L/2, T.

    B = (μ0 J/2) [u ln((r2 + √(r2² + u²))/(r1 + √(r1² + u²)))]_{u = z − L/2}^{u = z + L/2}.
    """
    z = np.asarray(z, dtype=float)

    def f(u):
        return u * np.log((r2 + np.hypot(r2, u)) / (r1 + np.hypot(r1, u)))

    return 0.5 * MU0 * current_density * (f(z + length / 2) - f(z - length / 2))


def cylinder_magnet_bz(z: ArrayLike, radius: float, length: float,
                       remanence: float) -> np.ndarray:
    """On-axis B_z of an axially magnetised (rigid, μ_rec = 1) cylinder centred at z = 0, T.

    Equivalent to a current sheet with n I = B_r/μ0, valid inside and outside the magnet.
    """
    return thin_solenoid_bz(z, radius, length, remanence / MU0, 1.0)


def ring_magnet_bz(z: ArrayLike, r_in: float, r_out: float, length: float,
                   remanence: float) -> np.ndarray:
    """On-axis B_z of an axially magnetised (rigid, μ_rec = 1) ring centred at z = 0, T.

    The ring is the cylinder of radius ``r_out`` minus that of radius ``r_in`` (superposition
    of magnetisations), so B_z is the difference of two :func:`cylinder_magnet_bz`, each
    B = (B_r/2) [(z + L/2)/√(R² + (z + L/2)²) − (z − L/2)/√(R² + (z − L/2)²)], valid inside
    and outside the magnet. Radii, length L and z in m, ``remanence`` B_r in T.
    """
    return (cylinder_magnet_bz(z, r_out, length, remanence)
            - cylinder_magnet_bz(z, r_in, length, remanence))


def loop_vector_potential(a: float, r: ArrayLike, z: ArrayLike, current: float = 1.0):
    """A_φ of a circular loop (radius a, at z = 0, current I) at (r, z), T m.

    A_φ = (μ0 I/(π k)) √(a/r) [(1 − k²/2) K(k²) − E(k²)], k² = 4 a r/((a + r)² + z²).
    """
    r, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(z, dtype=float))
    rs = np.where(r > 0, r, 1.0)
    m = 4 * a * rs / ((a + rs) ** 2 + z**2)
    k = np.sqrt(m)
    val = MU0 * current / (np.pi * k) * np.sqrt(a / rs) * ((1 - m / 2) * ellipk(m) - ellipe(m))
    return np.where(r > 0, val, 0.0)


def thick_solenoid_potential(r: ArrayLike, z: ArrayLike, r1: float, r2: float, length: float,
                             current_density: float, n_gauss: int = 24) -> np.ndarray:
    """A_φ of the uniform thick solenoid at points away from the winding, T m.

    Gauss–Legendre quadrature (``n_gauss``² points) of loop potentials over the cross-section;
    accurate to ~1e-12 relative at distances beyond a few winding sizes.
    """
    x, w = np.polynomial.legendre.leggauss(n_gauss)
    rr = 0.5 * (r2 - r1) * x + 0.5 * (r1 + r2)
    zz = 0.5 * length * x
    wr, wz = 0.5 * (r2 - r1) * w, 0.5 * length * w
    r, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(z, dtype=float))
    out = np.zeros(r.shape)
    for ai, wi in zip(rr, wr, strict=True):
        for zj, wj in zip(zz, wz, strict=True):
            out += wi * wj * loop_vector_potential(ai, r, z - zj)
    return current_density * out


def loop_mutual_inductance(a: ArrayLike, b: ArrayLike, d: ArrayLike) -> np.ndarray:
    """Mutual inductance of coaxial circular filaments (radii a, b, axial distance d), H.

    M = μ0 √(ab) [(2/k − k) K(k²) − (2/k) E(k²)], k² = 4ab/((a + b)² + d²).
    """
    a, b, d = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (a, b, d)))
    m = 4 * a * b / ((a + b) ** 2 + d**2)
    k = np.sqrt(m)
    return MU0 * np.sqrt(a * b) * ((2 / k - k) * ellipk(m) - 2 / k * ellipe(m))


def rectangle_gmd(b: float, c: float) -> float:
    """Geometric mean distance of a b × c rectangle from itself, m (Maxwell's formula)."""
    d = np.hypot(b, c)
    ln_g = (np.log(d) - (b / c) ** 2 / 12 * np.log(1 + (c / b) ** 2)
            - (c / b) ** 2 / 12 * np.log(1 + (b / c) ** 2)
            + 2 / 3 * (b / c) * np.arctan(c / b) + 2 / 3 * (c / b) * np.arctan(b / c) - 25 / 12)
    return float(np.exp(ln_g))


def coil_inductance_filaments(r1: float, r2: float, length: float, turns: float,
                              n_r: int, n_z: int) -> float:
    """Inductance of a uniform rectangular-section coil by summing filament mutuals, H.

    The section is split into n_r × n_z cells of N/(n_r n_z) turns each; cell pairs couple by
    :func:`loop_mutual_inductance`; a cell's self term is μ0 a (ln(8a/g) − 2) with g its GMD
    (thin-ring formula, Grover ch. 13). The error falls as the cells shrink (use Richardson).
    """
    dr, dz = (r2 - r1) / n_r, length / n_z
    rc = r1 + dr * (np.arange(n_r) + 0.5)
    zc = -length / 2 + dz * (np.arange(n_z) + 0.5)
    rr, zz = (x.ravel() for x in np.meshgrid(rc, zc, indexing="ij"))
    n = rr.size
    i, j = np.triu_indices(n, k=1)
    mutual = loop_mutual_inductance(rr[i], rr[j], zz[i] - zz[j])
    g = rectangle_gmd(dr, dz)
    self_terms = MU0 * rr * (np.log(8 * rr / g) - 2.0)
    per_cell = turns / n
    return float(per_cell**2 * (np.sum(self_terms) + 2.0 * np.sum(mutual)))


def dipole_force(m1: float, m2: float, distance: float) -> float:
    """Attractive force between coaxial, co-aligned point dipoles, N: 3 μ0 m1 m2/(2π d⁴)."""
    return 3.0 * MU0 * m1 * m2 / (2.0 * np.pi * distance**4)


def sphere_interior_h(h0: float, mu_r: float) -> float:
    """Uniform H inside a linear sphere (μ_r) in a uniform field H0, A/m: 3 H0/(μ_r + 2)."""
    return 3.0 * h0 / (mu_r + 2.0)
