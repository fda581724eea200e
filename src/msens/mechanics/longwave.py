"""Long-wavelength (Nesterenko) speeds of sound and solitary waves in a chain of spheres.

Pure functions of the bead diameter ``a`` (m), Young's modulus ``E`` (Pa), Poisson's ratio
``nu`` and density ``rho`` (kg/m^3) of identical elastic spheres in Hertzian contact. They
accept floats or NumPy arrays (broadcast).

Force convention (Nesterenko, *Dynamics of Heterogeneous Materials*, Springer 2001, §1.3;
Sen, Hong, Bang, Avalos & Doney, Phys. Rep. 462 (2008) 21, Eq. 20-22): ``F_m`` is the
**maximum total contact force** in the wave, i.e. static precompression plus dynamic part,
and ``f_r = F_m / F0 >= 1``. With ``F0 -> 0`` the precompressed speed tends to the
uncompressed one, and with ``f_r -> 1`` it tends to the sound speed ``c0`` (both checked
in tests/mechanics/test_longwave.py).

The numerical prefactors 0.6802 and 0.9314 are those of the paper (its Eq. 3-5); the exact
values are sqrt(8/15) (81/pi^3)^(1/6) / 2^(1/3) = 0.68015... and (81/(4 pi^3))^(1/6) =
0.93145..., a relative difference below 1e-4.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Prefactor of the uncompressed solitary-wave speed (paper Eq. 3, Nesterenko 2001).
C_SOLITON = 0.6802
#: Prefactor of the long-wavelength sound speed (paper Eq. 5, Nesterenko 2001).
C_SOUND = 0.9314


def soliton_speed_uncompressed(F_m: ArrayLike, a: float, E: float, nu: float,
                               rho: float) -> np.ndarray | float:
    """Solitary-wave speed in an uncompressed chain.

    V_s = 0.6802 (2E / (a rho^{3/2} (1 - nu^2)))^{1/3} F_m^{1/6}

    Parameters
    ----------
    F_m : float or ndarray
        Maximum contact force in the wave, N (>= 0).
    a : float
        Bead diameter, m.
    E, nu, rho : float
        Young's modulus (Pa), Poisson's ratio (-), density (kg/m^3) of the beads.

    Returns
    -------
    float or ndarray
        Speed, m/s, shape of ``F_m``.
    """
    F_m = np.asarray(F_m, dtype=float)
    out = C_SOLITON * (2.0 * E / (a * rho**1.5 * (1.0 - nu**2))) ** (1.0 / 3.0) * F_m ** (1.0 / 6.0)
    return out[()] if out.ndim == 0 else out


def sound_speed(F0: ArrayLike, a: float, E: float, nu: float, rho: float) -> np.ndarray | float:
    """Long-wavelength sound speed of a chain under static precompression ``F0``.

    c0 = 0.9314 (4 E^2 F0 / (a^2 rho^3 (1 - nu^2)^2))^{1/6}

    Equals a sqrt(k/m) with the linearised Hertz stiffness k = (3/2) A^{2/3} F0^{1/3}.

    Parameters
    ----------
    F0 : float or ndarray
        Static contact force, N (>= 0).
    a, E, nu, rho : float
        As in :func:`soliton_speed_uncompressed`.

    Returns
    -------
    float or ndarray
        Speed, m/s, shape of ``F0``.
    """
    F0 = np.asarray(F0, dtype=float)
    out = C_SOUND * (4.0 * E**2 * F0 / (a**2 * rho**3 * (1.0 - nu**2) ** 2)) ** (1.0 / 6.0)
    return out[()] if out.ndim == 0 else out


def soliton_speed_precompressed(F_m: ArrayLike, F0: ArrayLike, a: float, E: float, nu: float,
                                rho: float) -> np.ndarray | float:
    """Solitary-wave speed in a precompressed chain.

    V_s = c0 (f_r^{2/3} - 1)^{-1} sqrt((4/15)(3 + 2 f_r^{5/3} - 5 f_r^{2/3})),  f_r = F_m / F0

    The expression is 0/0 at f_r = 1, where its limit is c0; for |f_r - 1| < 1e-4 a
    second-order series is used instead to avoid cancellation.

    Parameters
    ----------
    F_m : float or ndarray
        Maximum total contact force in the wave (static + dynamic), N; must be >= F0.
    F0 : float or ndarray
        Static precompression, N (> 0).
    a, E, nu, rho : float
        As in :func:`soliton_speed_uncompressed`.

    Returns
    -------
    float or ndarray
        Speed, m/s, broadcast shape of ``F_m`` and ``F0``.
    """
    F_m, F0 = np.broadcast_arrays(np.asarray(F_m, dtype=float), np.asarray(F0, dtype=float))
    c0 = np.asarray(sound_speed(F0, a, E, nu, rho))
    f_r = F_m / F0
    s = f_r ** (1.0 / 3.0)  # f_r = s^3
    g = s**2 - 1.0
    num = (4.0 / 15.0) * (3.0 + 2.0 * s**5 - 5.0 * s**2)
    near = np.abs(f_r - 1.0) < 1e-4
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.sqrt(np.where(near, 1.0, num)) / np.where(near, 1.0, g)
    # Series about s = 1 (e = s - 1): V/c0 = 1 + e/6 + e^2/36 + O(e^3), error < 1e-13 here.
    e = s - 1.0
    ratio = np.where(near, 1.0 + e / 6.0 + e**2 / 36.0, ratio)
    out = c0 * ratio
    return out[()] if out.ndim == 0 else out
