"""``wall_stiffness``: the wall is not the bead steel (a softer base).

Parameter ``wall_youngs_modulus_pa`` sets the wall's Young's modulus in the Hertz prefactor of
the sphere-on-flat wall contact (A = (4/3) E* sqrt(R), 1/E* = (1-nu^2)/E + (1-nu_w^2)/E_w),
keeping the study's wall Poisson ratio. Baseline: the study's wall (steel, 200 GPa). A softer
wall holds the pulse longer: the reflected pulse comes later and broader.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.mechanics.hertz import hertz_sphere_flat

NAME = "wall_stiffness"
PARAM = "wall_youngs_modulus_pa"


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    # 2 GPa (hard polymer) to 1000 GPa (tungsten carbide is ~600 GPa)
    return (Parameter(PARAM, 2e9, 1000e9, log=True, plausible=(1e9, 1200e9),
                      reason="1 GPa (hard polymer) to 1200 GPa (diamond, the stiffest solid)",
                      floor=0.05 * float(ctx.study.chain.wall.youngs_modulus_pa),
                      floor_reason="5 %: the spread of the modulus within one steel or alloy "
                      "grade"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: float(ctx.study.chain.wall.youngs_modulus_pa)}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    c = ctx.study.chain
    stiffness = np.array(state.chain.stiffness)
    stiffness[-1] = hertz_sphere_flat(c.youngs_modulus_pa, c.poisson_ratio,
                                      0.5 * c.bead_diameter_m, float(params[PARAM]),
                                      c.wall.poisson_ratio)
    return dataclasses.replace(state,
                               chain=dataclasses.replace(state.chain, stiffness=stiffness))


EFFECT = Effect(name=NAME, description="Young's modulus of the wall (Pa)",
                space=_space, baseline=_baseline, apply=_apply)
