"""The bead steel's magnetoelastic law from the B–H table the field model uses.

The field solver takes the steel's normal B–H curve as a table (``[field] steel_bh``); the
Villari law (:mod:`msens.magnetics.magnetoelastic`) needs Jiles–Atherton–Sablik anhysteretic
parameters. So that both describe the same steel, the anhysteretic (M_s, a, α) is fitted to
the table by least squares on the relative misfit B_model(H_i)/B_i − 1 over the points with
H > 0, started from the design.md §7 defaults, the procedure that gave the stored 1018 fit
(:data:`msens.params.magnetostriction_data.STEEL_1018_FIT`). The magnetostriction coefficients and
the coupling κ are kept from that law: a B–H table says nothing about them.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from msens.field.geometry import same_bh
from msens.magnetics.magnetoelastic import DEFAULT_STEEL, JilesAthertonSablik, flux_density
from msens.params.magnetostriction_data import JA_DEFAULTS_STEEL
from msens.params.materials import STEEL_1018_BH, BHCurve


def fit_anhysteretic(bh: BHCurve, base: JilesAthertonSablik = JA_DEFAULTS_STEEL,
                     ) -> tuple[JilesAthertonSablik, float]:
    """Least-squares JAS anhysteretic for a normal B–H curve.

    Parameters
    ----------
    bh : BHCurve
        Normal magnetisation curve (T against A/m), strictly increasing from (0, 0).
    base : JilesAthertonSablik
        Start values, and the source of the magnetostriction coefficients and κ.

    Returns
    -------
    law : JilesAthertonSablik
        ``base`` with the fitted M_s (A/m), a (A/m) and α (-).
    rms_misfit : float
        Root-mean-square relative misfit of B over the table's points with H > 0.
    """
    h = np.asarray(bh.h, dtype=float)[1:]
    b = np.asarray(bh.b, dtype=float)[1:]

    def law_of(p: np.ndarray) -> JilesAthertonSablik:
        return dataclasses.replace(base, Ms=float(p[0]), a=float(p[1]), alpha=float(p[2]))

    def residual(p: np.ndarray) -> np.ndarray:
        return flux_density(law_of(p), h) / b - 1.0

    sol = least_squares(residual, [base.Ms, base.a, base.alpha], x_scale=[1e6, 100.0, 1e-4],
                        bounds=([1e4, 1.0, 0.0], [1e8, 1e6, 1e-2]), xtol=1e-12, ftol=1e-12)
    law = dataclasses.replace(
        law_of(sol.x),
        source=f"Ms, a, alpha: least-squares fit to the B-H table '{bh.name}' "
               f"(msens.magnetics.steel_law); magnetostriction and coupling: {base.source}")
    return law, float(np.sqrt(np.mean(sol.fun**2)))


def law_for_steel(bh: BHCurve) -> JilesAthertonSablik:
    """Magnetoelastic law of a bead steel given by its B–H table.

    The default 1018 curve gets the stored fit :data:`msens.magnetics.magnetoelastic.DEFAULT_STEEL`
    itself (so results and caches of the default studies do not move); any other table its
    own :func:`fit_anhysteretic`.
    """
    if same_bh(bh, STEEL_1018_BH):
        return DEFAULT_STEEL
    return _fitted(bh.name, tuple(map(float, bh.b)), tuple(map(float, bh.h)))


@lru_cache(maxsize=16)
def _fitted(name: str, b: tuple[float, ...], h: tuple[float, ...]) -> JilesAthertonSablik:
    curve = BHCurve(name=name, b=np.array(b), h=np.array(h), source="")
    return fit_anhysteretic(curve)[0]
