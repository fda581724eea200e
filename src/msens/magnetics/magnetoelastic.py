"""Magnetoelastic constitutive laws M(H, σ): the Jiles–Atherton–Sablik anhysteretic.

The material state is the anhysteretic magnetisation under a field H along a uniaxial stress σ
(tension > 0), from the mean-field free energy per volume [SJ93, J95]

    Ψ(M; H, σ) = μ₀ a M_s I(M/M_s) − μ₀ H M − μ₀ α M²/2 − κ σ λ(M, σ),   I'(m) = L⁻¹(m),

whose minimum ∂Ψ/∂M = 0 is M = M_s L(H_e/a) with the effective field
H_e = H + α M + (κ σ/μ₀) ∂λ/∂M, L(x) = coth x − 1/x (Langevin). The equation is implicit in M;
it is solved in x = H_e/a, where it reads Φ(x) = a x − α M_s L(x) − (κσ/μ₀) λ_M(M_s L(x)) = H
and M = M_s L(x) stays inside (−M_s, M_s) by construction.

Derivatives come from implicit differentiation of Φ(x; H, σ) = H:
∂M/∂H = M_s L'(x)/Φ_x and ∂M/∂σ = (κ/μ₀)(λ_M + σ λ_Mσ) ∂M/∂H. The Gibbs energy
G(H, σ) = min_M Ψ gives B-part −∂G/∂H = μ₀M and strain −∂G/∂σ = ε = κ(λ + σ ∂λ/∂σ), so the
Maxwell relation (∂B/∂σ)_H = (∂ε/∂H)_σ holds exactly; with κ = 1 and σ = 0, ε = λ and it is
the textbook (∂B/∂σ)_H = (∂λ/∂H)_σ. With Sablik–Jiles' κ = 3/2 the model's conjugate strain is
(3/2)λ: d is 1.5 times what λ read as the measured strain would imply (documented choice).

References: see :mod:`msens.params.magnetostriction_data`; [DH09] L. Daniel, O. Hubert, "An
equivalent stress for the influence of multiaxial stress on the magnetic behavior",
J. Appl. Phys. 105, 07A313 (2009).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from msens.errors import InputError, require
from msens.params.magnetostriction_data import STEEL_1018_FIT, JilesAthertonSablik
from msens.params.units import MU0

__all__ = [
    "DEFAULT_STEEL",
    "JilesAthertonSablik",
    "PiezomagneticCoefficient",
    "anhysteretic_magnetisation",
    "differential_susceptibility",
    "equivalent_uniaxial_stress",
    "flux_density",
    "langevin",
    "langevin_derivative",
    "magnetoelastic_strain",
    "magnetostriction",
    "piezomagnetic_coefficient",
    "stress_sensitivity",
    "unique_stress_range",
    "villari_reversal_field",
]

#: Default low-carbon steel: the anhysteretic fitted to the FEMM 1018 B–H curve (the curve
#: the field solver uses), with the [J95] magnetostriction and κ = 3/2. See
#: :mod:`msens.params.magnetostriction_data` for both sets and their sources.
DEFAULT_STEEL: JilesAthertonSablik = STEEL_1018_FIT

# Below |x| = 1 the Langevin function and its derivative use their Taylor series: the closed
# forms subtract 1/x and lose ~3 eps/x² relative accuracy (4e-14 at x = 0.1, 7e-16 at x = 1).
# coth x − 1/x = Σ_{n≥1} 2^{2n} B_{2n} x^{2n−1}/(2n)! converges for |x| < π; 18 terms leave
# (1/π)^{36} ≈ 1e-18 relative at |x| = 1.
_SERIES_X = 1.0
_N_SERIES = 18


def _bernoulli_even(n_max: int) -> list[Fraction]:
    """Exact B_0..B_{n_max} (Akiyama–Tanigawa); scipy's float recursion loses digits."""
    a: list[Fraction] = []
    out = []
    for m in range(n_max + 1):
        a.append(Fraction(1, m + 1))
        for j in range(m, 0, -1):
            a[j - 1] = j * (a[j - 1] - a[j])
        out.append(a[0])
    return out


_B = _bernoulli_even(2 * _N_SERIES)
_C = np.array([float(Fraction(2 ** (2 * n), math.factorial(2 * n)) * _B[2 * n])
               for n in range(1, _N_SERIES + 1)])  # 1/3, -1/45, 2/945, ...
_MAX_ITER = 200


def _even_series(coef: NDArray, x2: NDArray) -> NDArray:
    """Σ_k coef[k] x^{2k} by Horner."""
    out = np.zeros_like(x2)
    for c in coef[::-1]:
        out = out * x2 + c
    return out


def langevin(x: ArrayLike) -> NDArray[np.float64]:
    """Langevin function L(x) = coth x − 1/x, odd, |L| < 1, L ≈ x/3 near 0.

    Parameters
    ----------
    x : array_like
        Argument, dimensionless, any shape.

    Returns
    -------
    ndarray
        L(x), same shape as ``x``.
    """
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < _SERIES_X
    xs = np.where(small, x, 0.0)  # series only where it converges fast
    series = xs * _even_series(_C, xs * xs)
    xd = np.where(small, 1.0, x)  # closed form away from 0
    direct = 1.0 / np.tanh(xd) - 1.0 / xd
    return np.where(small, series, direct)


def langevin_derivative(x: ArrayLike) -> NDArray[np.float64]:
    """Derivative L'(x) = 1/x² − 1/sinh² x, even, 0 < L' ≤ 1/3.

    Parameters
    ----------
    x : array_like
        Argument, dimensionless, any shape.

    Returns
    -------
    ndarray
        L'(x), same shape as ``x``.
    """
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < _SERIES_X
    xs = np.where(small, x, 0.0)
    series = _even_series(_C * np.arange(1, 2 * _N_SERIES, 2), xs * xs)
    ax = np.where(small, 1.0, np.abs(x))
    e = np.exp(-2.0 * ax)  # 1/sinh² x = 4 e^{-2|x|}/(1 − e^{-2|x|})², no overflow
    direct = 1.0 / ax**2 - 4.0 * e / (1.0 - e) ** 2
    return np.where(small, series, direct)


# --- magnetostriction λ(M, σ) = γ₁(σ) M² + γ₂(σ) M⁴ and its derivatives ---------------------

def _gammas(law: JilesAthertonSablik, sigma: NDArray) -> tuple[NDArray, NDArray]:
    return law.gamma11 + law.gamma12 * sigma, law.gamma21 + law.gamma22 * sigma


def _lam(law, m, sigma):
    g1, g2 = _gammas(law, sigma)
    m2 = m * m
    return m2 * (g1 + g2 * m2)


def _lam_m(law, m, sigma):
    g1, g2 = _gammas(law, sigma)
    return m * (2.0 * g1 + 4.0 * g2 * m * m)


def _lam_mm(law, m, sigma):
    g1, g2 = _gammas(law, sigma)
    return 2.0 * g1 + 12.0 * g2 * m * m


def _lam_s(law, m):
    m2 = m * m
    return m2 * (law.gamma12 + law.gamma22 * m2)


def _lam_ms(law, m):
    return m * (2.0 * law.gamma12 + 4.0 * law.gamma22 * m * m)


# --- the implicit solve ---------------------------------------------------------------------

def _phi_and_slope(law, x, h, sigma):
    """Residual Φ(x) − H, its slope Φ_x and the size of its terms (for rounding), A/m."""
    m = law.Ms * langevin(x)
    k = law.coupling * sigma / MU0
    terms = (law.a * x, law.alpha * m, k * _lam_m(law, m, sigma), h)
    phi = terms[0] - terms[1] - terms[2] - terms[3]
    slope = law.a - law.Ms * langevin_derivative(x) * (law.alpha + k * _lam_mm(law, m, sigma))
    return phi, slope, sum(np.abs(t) for t in terms)


def _as_inputs(law: JilesAthertonSablik, H: ArrayLike, sigma: ArrayLike):
    h = np.asarray(H, dtype=float)
    s = np.asarray(sigma, dtype=float)
    require(bool(np.all(np.isfinite(h))), "magnetoelastic: field H must be finite (A/m)")
    require(bool(np.all(np.isfinite(s))), "magnetoelastic: stress sigma must be finite (Pa)")
    if s.size:
        lo, hi = unique_stress_range(law)
        smin, smax = float(s.min()), float(s.max())
        if smin < lo or smax > hi:
            raise InputError(
                f"magnetoelastic: stress sigma in [{smin:.4g}, {smax:.4g}] Pa is outside "
                f"[{lo:.4g}, {hi:.4g}] Pa, where the JAS anhysteretic of this material has a "
                "unique solution (the polynomial lambda(M, sigma) is not valid that far)"
            )
    return np.broadcast_arrays(h, s)


def _solve_x(law: JilesAthertonSablik, h: NDArray, s: NDArray) -> NDArray:
    """x = H_e/a solving Φ(x; H, σ) = H: bracketed Newton with bisection fallback."""
    k = law.coupling * np.abs(s) / MU0
    g1, g2 = _gammas(law, s)
    # |α M + kσ λ_M| ≤ C for |M| ≤ M_s, so Φ(x) − H changes sign on [(H−C)/a, (H+C)/a].
    c = law.alpha * law.Ms + k * (2 * np.abs(g1) * law.Ms + 4 * np.abs(g2) * law.Ms**3)
    lo = (h - c) / law.a - 1e-12
    hi = (h + c) / law.a + 1e-12
    x = np.clip(h / (law.a - law.alpha * law.Ms / 3.0), lo, hi)
    active = np.ones(x.shape, dtype=bool)
    step_prev = step_prev2 = hi - lo
    for _ in range(_MAX_ITER):
        phi, slope, size = _phi_and_slope(law, x, h, s)
        neg = phi < 0.0
        lo = np.where(neg, x, lo)
        hi = np.where(neg, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = x - phi / slope
        # Newton only strictly inside the bracket and when it at least halves the step of
        # two iterations ago (as in Numerical Recipes' rtsafe); otherwise bisect.
        ok = ((slope > 0.0) & (newton > lo) & (newton < hi)
              & (np.abs(newton - x) <= 0.5 * step_prev2))
        # Converged when the Newton step is down to the rounding of Φ (Newton then cycles
        # between neighbouring floats) or to a few ulps of x.
        noise = 8.0 * np.finfo(float).eps * size / np.maximum(np.abs(slope), 1e-300)
        done = (phi == 0.0) | ((slope > 0.0) & (np.abs(newton - x)
                                                <= np.maximum(2e-15 * np.abs(x), noise)))
        x_new = np.where(ok | done, newton, 0.5 * (lo + hi))
        step_prev2, step_prev = step_prev, np.abs(x_new - x)
        # converged entries stay put: a bisection step from an exact root would leave it
        x = np.where(active, np.where(phi == 0.0, x, x_new), x)
        active &= ~done
        if not active.any():
            return x
    # Φ is monotone inside unique_stress_range, so the safeguarded Newton cannot stall
    raise RuntimeError(f"magnetoelastic: root solve did not converge in {_MAX_ITER} steps")


def anhysteretic_magnetisation(law: JilesAthertonSablik, H: ArrayLike,
                               sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Anhysteretic magnetisation M(H, σ) of the JAS law.

    Parameters
    ----------
    law : JilesAthertonSablik
    H : array_like
        Field along the stress axis, A/m.
    sigma : array_like
        Uniaxial stress along H, Pa (tension > 0); broadcasts against ``H``.

    Returns
    -------
    ndarray
        M, A/m, shape of ``broadcast(H, sigma)``; odd in H, |M| < M_s.

    Raises
    ------
    InputError
        Non-finite input, or σ outside :func:`unique_stress_range`.
    """
    h, s = _as_inputs(law, H, sigma)
    return law.Ms * langevin(_solve_x(law, h, s))


def _state(law, H, sigma):
    """M, ∂M/∂H, the conjugate-strain slope ∂ε/∂M and σ at the solved state."""
    h, s = _as_inputs(law, H, sigma)
    x = _solve_x(law, h, s)
    m = law.Ms * langevin(x)
    _, slope, _ = _phi_and_slope(law, x, h, s)
    chi = law.Ms * langevin_derivative(x) / slope
    de_dm = law.coupling * (_lam_m(law, m, s) + s * _lam_ms(law, m))
    return m, chi, de_dm, s


def differential_susceptibility(law: JilesAthertonSablik, H: ArrayLike,
                                sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Anhysteretic differential susceptibility (∂M/∂H)_σ, dimensionless.

    Parameters and raises as :func:`anhysteretic_magnetisation`. At H = σ = 0 it is
    M_s/(3a − α M_s).
    """
    return _state(law, H, sigma)[1]


def stress_sensitivity(law: JilesAthertonSablik, H: ArrayLike,
                       sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """(∂M/∂σ)_H by implicit differentiation, A/m/Pa.

    Equals (κ/μ₀)(∂λ/∂M + σ ∂²λ/∂M∂σ) (∂M/∂H)_σ: zero at H = 0 (λ is even in M), and it
    changes sign where ∂λ/∂M + σ ∂²λ/∂M∂σ does (the Villari reversal).
    Parameters and raises as :func:`anhysteretic_magnetisation`.
    """
    _, chi, de_dm, _ = _state(law, H, sigma)
    return de_dm * chi / MU0


def piezomagnetic_coefficient(law: JilesAthertonSablik, H: ArrayLike,
                              sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Linear piezomagnetic coefficient d(H) = (∂B/∂σ)_H = μ₀ (∂M/∂σ)_H, T/Pa.

    A small stress change Δσ along the bias field H changes the flux density by d Δσ.
    Odd in H. Parameters and raises as :func:`anhysteretic_magnetisation`.
    """
    return MU0 * stress_sensitivity(law, H, sigma)


def flux_density(law: JilesAthertonSablik, H: ArrayLike,
                 sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """B = μ₀ (H + M(H, σ)), T, shape of ``broadcast(H, sigma)``."""
    h, s = np.broadcast_arrays(np.asarray(H, dtype=float), np.asarray(sigma, dtype=float))
    return MU0 * (h + anhysteretic_magnetisation(law, h, s))


def magnetostriction(law: JilesAthertonSablik, H: ArrayLike,
                     sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Magnetostriction λ(M(H, σ), σ) along the field, dimensionless strain."""
    h, s = np.broadcast_arrays(np.asarray(H, dtype=float), np.asarray(sigma, dtype=float))
    return _lam(law, anhysteretic_magnetisation(law, h, s), s)


def magnetoelastic_strain(law: JilesAthertonSablik, H: ArrayLike,
                          sigma: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Strain conjugate to σ in this model, ε = κ (λ + σ ∂λ/∂σ), dimensionless.

    It satisfies the Maxwell relation (∂B/∂σ)_H = (∂ε/∂H)_σ exactly; for κ = 1 at σ = 0
    it is λ itself.
    """
    h, s = np.broadcast_arrays(np.asarray(H, dtype=float), np.asarray(sigma, dtype=float))
    m = anhysteretic_magnetisation(law, h, s)
    return law.coupling * (_lam(law, m, s) + s * _lam_s(law, m))


@dataclass(frozen=True)
class PiezomagneticCoefficient:
    """d(H) as a callable, for pointwise evaluation in FE post-processing.

    Attributes
    ----------
    law : JilesAthertonSablik
    sigma : float
        Static (pre)stress the linearisation is taken about, Pa; 0 for the unloaded bead.

    Examples
    --------
    >>> d = PiezomagneticCoefficient(DEFAULT_STEEL)
    >>> d(np.array([[1e3, 5e3]])).shape
    (1, 2)
    """

    law: JilesAthertonSablik
    sigma: float = 0.0

    def __call__(self, H: ArrayLike) -> NDArray[np.float64]:
        """d at field magnitudes ``H`` (A/m, any shape), T/Pa, same shape."""
        return piezomagnetic_coefficient(self.law, H, self.sigma)


def _inverse_langevin(y: float) -> float:
    """x with L(x) = y for 0 ≤ y < 1 (scalar)."""
    if y == 0.0:
        return 0.0
    # L(x) < 1 − 1/x + 2e^{-2x}... so x < 1/(1 − y) + 1 brackets the root.
    return brentq(lambda t: float(langevin(t)) - y, 1e-12, 1.0 / (1.0 - y) + 1.0,
                  xtol=1e-15, rtol=1e-15, maxiter=200)


def villari_reversal_field(law: JilesAthertonSablik, sigma: float = 0.0) -> float:
    """Field H_r > 0 where d(H) changes sign (the Villari reversal), A/m.

    At the reversal ∂λ/∂M + σ ∂²λ/∂M∂σ = 0, i.e. M_r² = −(γ₁₁ + 2γ₁₂σ)/(2(γ₂₁ + 2γ₂₂σ));
    H_r = a L⁻¹(M_r/M_s) − α M_r − (κσ/μ₀) ∂λ/∂M(M_r) follows in closed form (no use of
    the forward solver). At σ = 0 it is the field of the λ(M) peak.

    Raises
    ------
    InputError
        If the law has no reversal below saturation at this stress.
    """
    sigma = float(sigma)
    num = law.gamma11 + 2.0 * law.gamma12 * sigma
    den = law.gamma21 + 2.0 * law.gamma22 * sigma
    mr2 = -num / (2.0 * den) if den != 0.0 else -1.0
    require(0.0 < mr2 < law.Ms**2,
            f"villari_reversal_field: no Villari reversal below saturation at sigma = {sigma:g} "
            "Pa for this material (d(H) keeps one sign)")
    mr = float(np.sqrt(mr2))
    x = _inverse_langevin(mr / law.Ms)
    s = np.asarray(sigma)
    return float(law.a * x - law.alpha * mr
                 - law.coupling * sigma / MU0 * _lam_m(law, np.asarray(mr), s))


@functools.lru_cache(maxsize=32)
def unique_stress_range(law: JilesAthertonSablik) -> tuple[float, float]:
    """Stresses (σ_min < 0 < σ_max), Pa, between which M(H, σ) is unique for every H.

    The solution is unique iff Φ_x = a − M_s L'(x)(α + (κσ/μ₀) ∂²λ/∂M²) > 0 for all x.
    This is checked on a dense x grid while scanning σ outward from 0 and bisecting the first
    failure; the returned bounds keep a 1 % margin. Beyond them the polynomial λ(M, σ) gives
    a multivalued (unphysical) anhysteretic.
    """
    x = np.concatenate([np.linspace(0.0, 60.0, 6001), np.geomspace(60.0, 1e5, 400)])
    lp = langevin_derivative(x)
    m = law.Ms * langevin(x)

    def ok(sigma: float) -> bool:
        s = np.asarray(sigma)
        slope = law.a - law.Ms * lp * (law.alpha + law.coupling * sigma / MU0
                                       * _lam_mm(law, m, s))
        return bool(np.all(slope > 0.0))

    def edge(sign: float) -> float:
        grid = sign * np.geomspace(1e3, 1e11, 321)
        prev = 0.0
        for sg in grid:
            if not ok(float(sg)):
                a, b = prev, float(sg)
                for _ in range(60):
                    mid = 0.5 * (a + b)
                    a, b = (mid, b) if ok(mid) else (a, mid)
                return 0.99 * a
            prev = float(sg)
        return float(prev)

    return edge(-1.0), edge(1.0)


def equivalent_uniaxial_stress(stress: ArrayLike, h_dir: ArrayLike) -> NDArray[np.float64]:
    """Uniaxial stress along the field equivalent to a multiaxial state [DH09], Pa.

    σ_eq = (3/2) ĥ·s·ĥ with s = σ − (tr σ/3) I the deviatoric stress and ĥ = h/|h|:
    uniaxial σ along ĥ gives σ_eq = σ, uniaxial σ across ĥ gives −σ/2, a hydrostatic
    pressure gives 0 (isochoric magnetostriction). This is Daniel and Hubert's simplified
    equivalent stress for isotropic materials with isotropic magnetostriction. Where h = 0
    the direction is undefined and σ_eq is returned as 0 (d(0) = 0 there anyway).

    Parameters
    ----------
    stress : array_like
        Either full tensors, shape (..., 3, 3), Pa, with ``h_dir`` shape (..., 3) in the same
        basis; or axisymmetric components [σ_rr, σ_zz, σ_θθ, σ_rz], shape (..., 4), Pa (the
        order of msens.mechanics.stress_sampling.stress_at), with ``h_dir`` = [h_r, h_z],
        shape (..., 2).
    h_dir : array_like
        Field direction (any length), broadcast against the stress batch shape.

    Returns
    -------
    ndarray
        σ_eq, Pa, the broadcast batch shape.

    Raises
    ------
    InputError
        If the shapes match neither form.
    """
    s = np.asarray(stress, dtype=float)
    h = np.asarray(h_dir, dtype=float)
    if s.ndim >= 2 and s.shape[-2:] == (3, 3):
        require(h.shape[-1:] == (3,), "equivalent_uniaxial_stress: for (..., 3, 3) stress "
                f"tensors h_dir must have shape (..., 3), got {h.shape}")
        hh = np.einsum("...i,...ij,...j->...", h, s, h)
        n2 = np.einsum("...i,...i->...", h, h)
        trace = np.trace(s, axis1=-2, axis2=-1)
    elif s.ndim >= 1 and s.shape[-1] == 4:
        require(h.shape[-1:] == (2,), "equivalent_uniaxial_stress: for axisymmetric stress "
                f"[srr, szz, stt, srz] h_dir must be [h_r, h_z], shape (..., 2), got {h.shape}")
        srr, szz, stt, srz = np.moveaxis(s, -1, 0)
        hr, hz = np.moveaxis(h, -1, 0)
        hh = srr * hr * hr + 2.0 * srz * hr * hz + szz * hz * hz
        n2 = hr * hr + hz * hz
        trace = srr + szz + stt
    else:
        raise InputError("equivalent_uniaxial_stress: stress must have shape (..., 3, 3) or "
                         f"(..., 4) [srr, szz, stt, srz], got {s.shape}")
    safe = np.where(n2 > 0.0, n2, 1.0)
    return np.where(n2 > 0.0, 1.5 * hh / safe - 0.5 * trace, 0.0)
