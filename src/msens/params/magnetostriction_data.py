"""Parameter sets for the Jiles–Atherton–Sablik (JAS) anhysteretic magnetoelastic law.

Each set is one frozen record with its citation (PyBaMM style); the laws that use them live
in :mod:`msens.magnetics.magnetoelastic`. All values SI.

The magnetostriction follows Sablik & Jiles [SJ93]: λ(M, σ) = γ₁(σ) M² + γ₂(σ) M⁴ with
γ₁ = γ₁₁ + γ₁₂ σ and γ₂ = γ₂₁ + γ₂₂ σ. γ₂ < 0 makes λ rise, peak and change sign at higher
magnetisation (iron and mild steel); the peak of λ(M) is where the Villari effect reverses.

References
----------
[SJ93] M. J. Sablik, D. C. Jiles, "Coupled magnetoelastic theory of magnetic and
       magnetostrictive hysteresis", IEEE Trans. Magn. 29(4), 2113-2123 (1993).
[J95]  D. C. Jiles, "Theory of the magnetomechanical effect", J. Phys. D 28, 1537-1546 (1995).
[JA86] D. C. Jiles, D. L. Atherton, "Theory of ferromagnetic hysteresis", J. Magn. Magn.
       Mater. 61, 48-60 (1986).
"""

from __future__ import annotations

from dataclasses import dataclass

from msens.errors import require


@dataclass(frozen=True)
class JilesAthertonSablik:
    """Anhysteretic Jiles–Atherton–Sablik magnetoelastic material.

    Effective field H_e = H + α M + (κ σ / μ₀) ∂λ/∂M, magnetisation M = M_s L(H_e / a).

    Attributes
    ----------
    Ms : float
        Saturation magnetisation M_s, A/m.
    a : float
        Langevin shape parameter, A/m.
    alpha : float
        Mean-field (domain coupling) parameter α, dimensionless.
    gamma11 : float
        M² coefficient of λ at zero stress, m²/A² (i.e. (A/m)⁻²).
    gamma12 : float
        Stress dependence of the M² coefficient, (A/m)⁻² Pa⁻¹.
    gamma21 : float
        M⁴ coefficient of λ at zero stress, (A/m)⁻⁴.
    gamma22 : float
        Stress dependence of the M⁴ coefficient, (A/m)⁻⁴ Pa⁻¹.
    coupling : float
        κ in the magnetoelastic field κ σ/μ₀ ∂λ/∂M. Sablik and Jiles use κ = 3/2 [SJ93, J95];
        κ = 1 is the choice for which λ itself is the strain thermodynamically conjugate to
        σ (see :func:`msens.magnetics.magnetoelastic.magnetoelastic_strain`).
    source : str
        Where the numbers come from; estimates say so.
    """

    Ms: float
    a: float
    alpha: float
    gamma11: float
    gamma12: float
    gamma21: float
    gamma22: float
    coupling: float
    source: str

    def __post_init__(self) -> None:
        require(self.Ms > 0.0, f"JilesAthertonSablik: Ms must be > 0 A/m, got {self.Ms!r}")
        require(self.a > 0.0, f"JilesAthertonSablik: a must be > 0 A/m, got {self.a!r}")
        require(self.alpha >= 0.0,
                f"JilesAthertonSablik: alpha must be >= 0, got {self.alpha!r}")
        require(self.coupling > 0.0,
                f"JilesAthertonSablik: coupling must be > 0, got {self.coupling!r}")
        # Without stress the anhysteretic must be single-valued: its slope in x = H_e/a is
        # a - alpha Ms L'(x) with max L' = 1/3 at x = 0.
        require(self.alpha * self.Ms < 3.0 * self.a,
                "JilesAthertonSablik: need alpha*Ms < 3a for a single-valued anhysteretic, "
                f"got alpha*Ms = {self.alpha * self.Ms:g} A/m, 3a = {3 * self.a:g} A/m")


# Magnetostriction coefficients of [J95] Table 1 (a steel; the same set is used in [SJ93]):
# gamma11 = 7e-18 (A/m)^-2, gamma12 = -1e-25 (A/m)^-2/Pa, gamma21 = -3.3e-30 (A/m)^-4,
# gamma22 = 2.1e-38 (A/m)^-4/Pa. These are the values widely quoted from those papers; they
# were not re-checked against the originals here, so treat them as an estimate for mild steel.
# At zero stress they give a peak lambda = gamma11^2/(4|gamma21|) = 3.7 ppm at
# M = 1.03e6 A/m (the Villari reversal), lambda = 0 at M = 1.46e6 A/m and lambda(Ms = 1.6e6)
# = -3.7 ppm: order 10 ppm with the sign change of iron and mild steel, as design.md §7 asks.
_GAMMA = dict(gamma11=7.0e-18, gamma12=-1.0e-25, gamma21=-3.3e-30, gamma22=2.1e-38)

#: JA anhysteretic parameters quoted in design.md §7 (M_s 1.6e6 A/m, a 560 A/m, α 7e-4; the
#: hysteresis parameters k, c are not used) with the [J95] magnetostriction; κ = 3/2.
#: The anhysteretic B(H) lies well above the FEMM 1018 curve at low field (see
#: :data:`STEEL_1018_FIT` and tests/verification/test_magnetoelastic_bh.py).
JA_DEFAULTS_STEEL = JilesAthertonSablik(
    Ms=1.6e6, a=560.0, alpha=7.0e-4, **_GAMMA, coupling=1.5,
    source="Ms, a, alpha: JA defaults quoted in design.md §7 (estimate); gamma: [J95] Table 1 "
           "as quoted (estimate for mild steel); coupling 3/2 [SJ93]",
)

#: Anhysteretic fitted to the FEMM 1018 B–H curve (:data:`msens.params.materials.STEEL_1018_BH`, the
#: curve the field solver uses): least squares (scipy.optimize.least_squares, from the
#: design.md §7 defaults) on the relative misfit B_model(H_i)/B_i − 1 over the 12 points with
#: H > 0; result rounded to 5 digits. Relative misfit: rms 5.7 %, max 14.8 % (at 795.8 A/m);
#: the design.md §7 defaults give rms 53 %, max 176 % (at 238.7 A/m). A Langevin anhysteretic
#: cannot follow the steep knee of a measured normal curve better than this. Magnetostriction
#: and κ as :data:`JA_DEFAULTS_STEEL`. Re-derived in tests/verification/test_magnetoelastic_bh.py.
STEEL_1018_FIT = JilesAthertonSablik(
    Ms=1.5719e6, a=825.70, alpha=4.8178e-4, **_GAMMA, coupling=1.5,
    source="Ms, a, alpha: least-squares fit to the FEMM 4.2 '1018 Steel' B-H curve (this "
           "module); gamma: [J95] Table 1 as quoted (estimate for mild steel); coupling 3/2 "
           "[SJ93]",
)
