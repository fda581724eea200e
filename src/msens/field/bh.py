"""Monotone B–H interpolation for nonlinear soft magnetic regions.

The table H(B) of a :class:`msens.params.materials.BHCurve` is interpolated with a shape-preserving
piecewise-cubic Hermite interpolant (PCHIP slopes, Fritsch & Carlson 1980), which keeps H(B)
strictly increasing when the data are, so the magnetic energy density w(B) = ∫ H dB is convex and
Newton's method has a unique solution to converge to. Beyond the last table point the curve
continues as a straight line of slope μ0 (the material is saturated: B = B_n + μ0 (H − H_n));
the interpolant's end slope is set to 1/μ0 so that dH/dB is continuous there.

The solver works with the reluctivity ν(|B|²) = H(|B|)/|B| and the differential (tangent)
reluctivity ν_d(|B|) = dH/dB. The Jacobian of H(B) = ν(|B|²) B with respect to B is
``ν I + (ν_d − ν) b̂ b̂ᵀ`` (b̂ = B/|B|), equal to ``ν I + 2 ν'(|B|²) B Bᵀ``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator, PPoly

from msens.errors import require
from msens.params.materials import BHCurve
from msens.params.units import MU0


@dataclass(frozen=True)
class MonotoneBH:
    """Monotone interpolant H(B) of a B–H table with linear (μ0) extrapolation.

    Attributes
    ----------
    curve : BHCurve
        The tabulated curve it was built from.
    h_of_b : CubicHermiteSpline
        H(B) on [0, B_n], A/m as a function of T.
    w_of_b : PPoly
        Energy density ∫_0^B H dB', J/m^3, on [0, B_n] (antiderivative of ``h_of_b``).
    """

    curve: BHCurve
    h_of_b: CubicHermiteSpline
    w_of_b: PPoly

    @property
    def b_max(self) -> float:
        """Last tabulated flux density B_n, T."""
        return float(self.curve.b[-1])

    @property
    def h_max(self) -> float:
        """Last tabulated field strength H_n, A/m."""
        return float(self.curve.h[-1])

    def field_strength(self, b: np.ndarray) -> np.ndarray:
        """H(|B|), A/m, for flux density magnitudes ``b`` (T, any shape, >= 0)."""
        b = np.asarray(b, dtype=float)
        inside = b <= self.b_max
        h_lin = self.h_max + (b - self.b_max) / MU0
        return np.where(inside, self.h_of_b(np.minimum(b, self.b_max)), h_lin)

    @cached_property
    def _dh_db(self) -> PPoly:
        return self.h_of_b.derivative()

    def differential_reluctivity(self, b: np.ndarray) -> np.ndarray:
        """ν_d = dH/dB, m/H, at magnitudes ``b`` (T, any shape)."""
        b = np.asarray(b, dtype=float)
        d = self._dh_db(np.minimum(b, self.b_max))
        return np.where(b <= self.b_max, d, 1.0 / MU0)

    def reluctivity(self, b: np.ndarray) -> np.ndarray:
        """Secant reluctivity ν = H/|B|, m/H; at |B| = 0 its limit dH/dB(0)."""
        b = np.asarray(b, dtype=float)
        small = b < 1e-9
        safe = np.where(small, 1.0, b)
        return np.where(small, self.differential_reluctivity(np.zeros_like(b)),
                        self.field_strength(safe) / safe)

    def reluctivity_derivative(self, b2: np.ndarray) -> np.ndarray:
        """dν/d(|B|²), m/(H T²), at squared magnitudes ``b2`` (T², any shape).

        Near |B| = 0 the quotient is ill-conditioned; it is evaluated at |B| >= 1e-6 T there.
        """
        b = np.maximum(np.sqrt(np.asarray(b2, dtype=float)), 1e-6)
        return (self.differential_reluctivity(b) - self.reluctivity(b)) / (2.0 * b**2)

    def energy_density(self, b: np.ndarray) -> np.ndarray:
        """Stored energy density w(|B|) = ∫_0^|B| H dB', J/m^3."""
        b = np.asarray(b, dtype=float)
        w_n = float(self.w_of_b(self.b_max))
        db = b - self.b_max
        w_lin = w_n + self.h_max * db + db**2 / (2.0 * MU0)
        return np.where(b <= self.b_max, self.w_of_b(np.minimum(b, self.b_max)), w_lin)


def monotone_bh(curve: BHCurve) -> MonotoneBH:
    """Build the monotone interpolant of a tabulated B–H curve.

    Parameters
    ----------
    curve : BHCurve
        Table starting at (0, 0) with B and H strictly increasing.

    Returns
    -------
    MonotoneBH

    Raises
    ------
    msens.errors.InputError
        If the table is too short, does not start at the origin or is not strictly increasing.
    """
    b = np.asarray(curve.b, dtype=float)
    h = np.asarray(curve.h, dtype=float)
    require(b.ndim == 1 and b.shape == h.shape and b.size >= 3,
            f"B-H curve '{curve.name}': b and h must be 1-D of equal length >= 3")
    require(b[0] == 0.0 and h[0] == 0.0, f"B-H curve '{curve.name}' must start at (0, 0)")
    require(bool(np.all(np.diff(b) > 0) and np.all(np.diff(h) > 0)),
            f"B-H curve '{curve.name}': B and H must be strictly increasing")
    slopes = PchipInterpolator(b, h).derivative()(b)
    # End slope 1/μ0 makes H'(B) continuous into the saturation line (a kink there would slow
    # Newton); it stays within the Fritsch–Carlson monotonicity bound 3 ΔH/ΔB of the last
    # interval for any physical table (checked).
    last_secant = (h[-1] - h[-2]) / (b[-1] - b[-2])
    require(1.0 / MU0 <= 3.0 * last_secant,
            f"B-H curve '{curve.name}': the last interval is too steep for a monotone join to "
            "the saturation line B = B_n + mu0 (H - H_n); extend the table to higher fields")
    slopes[-1] = 1.0 / MU0
    h_of_b = CubicHermiteSpline(b, h, slopes, extrapolate=False)
    return MonotoneBH(curve=curve, h_of_b=h_of_b, w_of_b=h_of_b.antiderivative())
