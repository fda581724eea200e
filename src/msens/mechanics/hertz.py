"""Hertz contact of elastic spheres (paper Eq. 1, 2, 7): the one home of its formulas.

A Hertz contact carries F = A delta^{3/2} (compressive positive, delta the approach of the
two centres, m). The prefactor is A = (4/3) E* sqrt(R*) with the effective modulus
1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 and effective radius R* = R1 R2 / (R1 + R2)
(Johnson, *Contact Mechanics*, CUP 1985, Eq. 4.22-4.23). A flat face (rod end, the wall
treated as a half-space) is a sphere of infinite radius, R* = R_s. The contact circle has the
radius a = (3 F R* / (4 E*))^{1/3} and a² = R* δ (Johnson Eq. 4.22).

Pure functions of floats or NumPy arrays (broadcast); units SI.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def effective_modulus(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike):
    """Contact modulus E* = 1 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2), Pa."""
    E1, nu1, E2, nu2 = (np.asarray(x, dtype=float) for x in (E1, nu1, E2, nu2))
    out = 1.0 / ((1.0 - nu1**2) / E1 + (1.0 - nu2**2) / E2)
    return out[()] if out.ndim == 0 else out


def identical_spheres_modulus(E: ArrayLike, nu: ArrayLike):
    """E* = E / (2 (1 - nu^2)) of two spheres of one material, Pa (:func:`effective_modulus`
    with the same material twice, in the rounding the field meshes were built with)."""
    out = np.asarray(E, dtype=float) / (2.0 * (1.0 - np.asarray(nu, dtype=float) ** 2))
    return out[()] if out.ndim == 0 else out


def hertz_sphere_sphere(E1: ArrayLike, nu1: ArrayLike, R1: ArrayLike,
                        E2: ArrayLike, nu2: ArrayLike, R2: ArrayLike):
    """Hertz prefactor A of two spheres, N/m^1.5.

    Parameters
    ----------
    E1, nu1, R1 : float or ndarray
        Young's modulus (Pa), Poisson's ratio (-) and radius (m) of sphere 1.
    E2, nu2, R2 : float or ndarray
        The same for sphere 2.

    Returns
    -------
    float or ndarray
        A = (4/3) E* sqrt(R1 R2 / (R1 + R2)); for identical spheres E sqrt(2R) / (3 (1 - nu^2))
        (paper Eq. 2).
    """
    R1, R2 = np.asarray(R1, dtype=float), np.asarray(R2, dtype=float)
    out = 4.0 / 3.0 * np.asarray(effective_modulus(E1, nu1, E2, nu2)) * np.sqrt(R1 * R2 / (R1 + R2))
    return out[()] if out.ndim == 0 else out


def hertz_sphere_flat(E_s: ArrayLike, nu_s: ArrayLike, R_s: ArrayLike,
                      E_f: ArrayLike, nu_f: ArrayLike):
    """Hertz prefactor A of a sphere on a flat face (rod end or half-space wall), N/m^1.5.

    Parameters
    ----------
    E_s, nu_s, R_s : float or ndarray
        Young's modulus (Pa), Poisson's ratio (-) and radius (m) of the sphere.
    E_f, nu_f : float or ndarray
        Young's modulus (Pa) and Poisson's ratio (-) of the flat body.

    Returns
    -------
    float or ndarray
        A = (4/3) E* sqrt(R_s) (paper Eq. 7, A_w).
    """
    R_s = np.asarray(R_s, dtype=float)
    out = 4.0 / 3.0 * np.asarray(effective_modulus(E_s, nu_s, E_f, nu_f)) * np.sqrt(R_s)
    return out[()] if out.ndim == 0 else out


def hertz_energy(A: ArrayLike, delta: ArrayLike):
    """Elastic energy stored in a Hertz contact, (2/5) A [delta]_+^{5/2}, J."""
    d = np.maximum(np.asarray(delta, dtype=float), 0.0)
    out = 0.4 * np.asarray(A, dtype=float) * d**2.5
    return out[()] if out.ndim == 0 else out


def hertz_approach(force: ArrayLike, A: ArrayLike):
    """Approach δ = ([F]_+ / A)^{2/3} of a Hertz contact carrying the force F (N), m.

    Its slope in F is infinite at F = 0: signals should use the chain's own approach there.
    """
    f = np.clip(np.asarray(force, dtype=float), 0.0, None)
    out = (f / np.asarray(A, dtype=float)) ** (2.0 / 3.0)
    return out[()] if out.ndim == 0 else out


def hertz_contact_radius(force: ArrayLike, R_eff: ArrayLike, E_eff: ArrayLike):
    """Radius a = (3 F R* / (4 E*))^{1/3} of the contact circle, m.

    Parameters
    ----------
    force : float or ndarray
        Contact force F, N (>= 0).
    R_eff : float or ndarray
        Effective radius R*, m (R/2 for two identical spheres).
    E_eff : float or ndarray
        Contact modulus E* (:func:`effective_modulus`), Pa.
    """
    out = (3.0 * np.asarray(force, dtype=float) * np.asarray(R_eff, dtype=float)
           / (4.0 * np.asarray(E_eff, dtype=float))) ** (1.0 / 3.0)
    return out[()] if out.ndim == 0 else out
