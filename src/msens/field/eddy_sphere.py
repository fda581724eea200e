"""Verification of the eddy-current solver: a conducting permeable sphere in a uniform field.

:func:`conducting_sphere` is the closed form (moment and mean internal field);
:func:`sphere_check` solves the same sphere with :mod:`msens.field.eddy` and compares.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from msens.field.eddy import (
    conductivity,
    dipole_moment,
    dissipated_power,
    mean_field_z,
    skin_depth,
    solve_harmonic,
)
from msens.field.mesh import AxiMesh
from msens.field.solve import MagnetostaticProblem
from msens.params.materials import SIGMA_1018
from msens.params.units import MU0, TWO_PI


def conducting_sphere(radius: float, mu_r: float, sigma: float, frequency: float,
                      h0: complex = 1.0) -> tuple[complex, complex]:
    """Exact moment and mean internal field of a conducting permeable sphere in H0 e^{jωt}.

    k = (1 − j)/δ (k² = −jωμσ, the e^{jωt} convention; the results depend on k² only),
    P = j1(kR), Q = kR j0(kR) − j1(kR):

        m = 2π R³ H0 (2 μ_r P − Q)/(μ_r P + Q),     ⟨H_z⟩ = 3 H0 P/(μ_r P + Q).

    Derivation: inside, A_φ = C j1(kρ) sin θ; outside, A_φ = μ0 (H0 ρ/2 + m/(4πρ²)) sin θ;
    continuity of A_φ (B_ρ) and of H_θ = −(1/(μρ)) ∂(ρA_φ)/∂ρ at ρ = R, with
    d(ρ j1(kρ))/dρ = kρ j0 − j1. The volume mean of B is ∮ n × A dS / V = μ0 (H0 + 2m/(4πR³)),
    and ⟨H⟩ = ⟨B⟩/μ. Limits: DC m = 4πR³H0(μ_r − 1)/(μ_r + 2), ⟨H_z⟩ = 3H0/(μ_r + 2);
    δ ≪ R/μ_r: m → −2πR³H0, ⟨H_z⟩ → 0.

    Parameters
    ----------
    radius : float
        R, m.
    mu_r : float
        Relative permeability.
    sigma : float
        S/m.
    frequency : float
        Hz (0: the static limit).
    h0 : complex
        Applied field phasor, A/m.

    Returns
    -------
    m : complex
        Dipole moment, A m².
    h_mean : complex
        Volume mean of H_z inside, A/m.
    """
    if frequency == 0 or sigma == 0:
        g = 0.5 + 0j  # P/Q at k → 0: (x/3)/(2x/3)
    else:
        x = complex(radius * (1 - 1j) / skin_depth(frequency, mu_r, sigma))
        if abs(x) < 0.5:
            # series (the cot form below cancels for small x): j1 = x/3 − x³/30 + x⁵/840
            # − x⁷/45360 + x⁹/3991680, Q = 2x/3 − 2x³/15 + x⁵/140 − x⁷/5670 + x⁹/399168
            x2 = x * x
            g = ((1 / 3 - x2 / 30 + x2**2 / 840 - x2**3 / 45360 + x2**4 / 3991680)
                 / (2 / 3 - 2 * x2 / 15 + x2**2 / 140 - x2**3 / 5670 + x2**4 / 399168))
        else:
            # P/Q = (1/x² − cot x / x)/(1 − 1/x² + cot x / x), finite for any |Im x|
            # (j1 and j0 themselves overflow for |Im x| > ~700)
            c = 1.0 / np.tan(x)
            g = (1 / x**2 - c / x) / (1 - 1 / x**2 + c / x)
    m = TWO_PI * radius**3 * h0 * (2 * mu_r * g - 1) / (mu_r * g + 1)
    return complex(m), complex(3 * h0 * g / (mu_r * g + 1))


def truncation_factor(moment: complex, h0: complex, r_out: float) -> complex:
    """H0/H_eff for a dipole inside a concentric spherical boundary where A_φ = μ0 H0 r/2.

    That boundary value forces the exterior solution μ0 [(H0 + c) ρ/2 + m/(4πρ²)] sin θ with
    c = −m/(2π r_out³): the sphere sees the uniform field H_eff = H0 + c instead of H0.
    A linear body's response scales with the applied field, so multiplying the computed
    moment and internal field by H0/H_eff gives the open-domain values (exact for a sphere
    at the sphere's centre; the correction is ~ 2 (R/r_out)³).
    """
    return complex(h0 / (h0 - moment / (TWO_PI * r_out**3)))


@dataclass(frozen=True)
class SphereCheck:
    """FE vs exact for the conducting sphere at one (μ_r, f).

    Attributes
    ----------
    mu_r, frequency, skin_depth : float
        –, Hz, m.
    moment, moment_exact : complex
        A m² (FE corrected for truncation by :func:`truncation_factor`).
    h_mean, h_mean_exact : complex
        Volume-mean H_z inside, A/m.
    power, power_identity : float
        FE eddy loss (ω²/2)∫σ|A|²dV and −(ωμ0/2) Im(m H0*) from the FE moment, W.
    dofs : int
    """

    mu_r: float
    frequency: float
    skin_depth: float
    moment: complex
    moment_exact: complex
    h_mean: complex
    h_mean_exact: complex
    power: float
    power_identity: float
    dofs: int

    @staticmethod
    def _errors(fe: complex, ex: complex) -> tuple[float, float]:
        rel = abs(abs(fe) / abs(ex) - 1.0)
        phase = abs(math.degrees(np.angle(fe / ex)))
        return rel, phase

    @property
    def moment_errors(self) -> tuple[float, float]:
        """(relative magnitude error, phase error in degrees) of the moment."""
        return self._errors(self.moment, self.moment_exact)

    @property
    def h_mean_errors(self) -> tuple[float, float]:
        """(relative magnitude error, phase error in degrees) of the mean internal H_z."""
        return self._errors(self.h_mean, self.h_mean_exact)


def sphere_check(mesh: AxiMesh, radius: float, r_out: float, mu_r: float,
                 frequencies: Sequence[float], sigma: float = SIGMA_1018,
                 h0: float = 1.0, correct_truncation: bool = True) -> list[SphereCheck]:
    """Solve the conducting sphere in a uniform field and compare with :func:`conducting_sphere`.

    Parameters
    ----------
    mesh : AxiMesh
        Subdomains ``sphere`` (centred at the origin) and ``air``, boundary ``outer`` (a half
        circle of radius ``r_out``), e.g. :func:`msens.field.eddy_geometry.layered_sphere_mesh`.
    radius, r_out : float
        Sphere and outer radius, m.
    mu_r : float
    frequencies : sequence of float
        Hz.
    sigma : float
        S/m.
    h0 : float
        Applied field, A/m (imposed as A_φ = μ0 H0 r/2 on ``outer``).
    correct_truncation : bool
        Apply :func:`truncation_factor` to the FE moment and field.
    """
    from msens.field.regions import Air, LinearMagnetic

    prob = MagnetostaticProblem(mesh, {"sphere": LinearMagnetic(mu_r), "air": Air()},
                                background_field=MU0 * h0)
    sols = solve_harmonic(prob, conductivity(mesh, {"sphere": sigma}), frequencies)
    out = []
    for s in sols:
        m, h = dipole_moment(s, "sphere"), mean_field_z(s, "sphere")
        p_id = -0.5 * s.omega * MU0 * float(np.imag(m * np.conj(h0)))
        if correct_truncation:
            c = truncation_factor(m, h0, r_out)
            m, h = m * c, h * c
        m_ex, h_ex = conducting_sphere(radius, mu_r, sigma, s.frequency, h0)
        out.append(SphereCheck(mu_r=mu_r, frequency=s.frequency,
                               skin_depth=skin_depth(s.frequency, mu_r, sigma),
                               moment=m, moment_exact=m_ex, h_mean=h, h_mean_exact=h_ex,
                               power=dissipated_power(s, "sphere"), power_identity=p_id,
                               dofs=s.dofs))
    return out


__all__ = ["SphereCheck", "conducting_sphere", "sphere_check", "truncation_factor"]
